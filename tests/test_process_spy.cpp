// lcm-spy (scripts/livo-spy: Debian's lcm.spy.Spy with the receive buffer of the URL) sees every channel
// of a four-process run: the demo log (6 s) replayed by lcm-logplayer into livo-preprocess,
// livo-estimator, livo-mapserver and livo-exporter in a private network namespace, lcm-spy under Xvfb
// in the same namespace, its channel table read from its window (--print-table) until every LIVO_*
// channel is listed with a decoded type, among them the large LIVO_LIDAR (~530 kB), LIVO_FRAME and
// LIVO_SUBMAP. Skipped without root (namespace), Xvfb, java or the jars, which CI provides.
// livo-test-bins: livo-sim livo-preprocess livo-estimator livo-mapserver livo-exporter livo_lcmtypes_jar livo_spy_jar
// livo-test-xserver: starts Xvfb (its tests run one at a time with the others that do)
#include "process_test_display.hpp"
#include "process_test_suite.hpp"
#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>

using namespace livo::test;

namespace {

const std::vector<std::string> kChannels = {"LIVO_IMU",        "LIVO_LIDAR",           "LIVO_CAMERA",
                                            "LIVO_FRAME",      "LIVO_MAP_QUERY",       "LIVO_SUBMAP",
                                            "LIVO_MAP_UPDATE", "LIVO_ODOMETRY",        "LIVO_REGISTERED_SCAN",
                                            "LIVO_ESTIMATOR_STATS", "LIVO_MAP_STATS"};

struct Row {
  std::string type, count, hz, largest;
};

/// The last table livo-spy printed (--print-table): channel -> row.
std::map<std::string, Row> lastTable(const std::string& out) {
  std::map<std::string, Row> rows;
  const auto at = out.rfind("# lcm-spy channels at");
  if (at == std::string::npos) return rows;
  std::istringstream in(out.substr(at));
  std::string line;
  std::getline(in, line);  // "# lcm-spy channels at T s"
  std::getline(in, line);  // header
  while (std::getline(in, line) && !line.empty() && line[0] != '#') {
    std::vector<std::string> f;
    std::istringstream cells(line);
    for (std::string c; std::getline(cells, c, '\t');) f.push_back(c);
    if (f.size() >= 9) rows[f[0]] = Row{f[1], f[2], f[3], f[8]};
  }
  return rows;
}

bool allListed(const std::map<std::string, Row>& t) {
  for (const auto& c : kChannels) {
    const auto it = t.find(c);
    if (it == t.end() || it->second.type.rfind("??", 0) == 0 || it->second.count == "0") return false;
  }
  return true;
}

}  // namespace

TEST(SpyNetns, ListsEveryChannelOfAFourProcessRun) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!haveTool("lcm-logplayer")) LIVO_SKIP() << "lcm-logplayer missing (Debian package liblcm-bin)";
  if (!haveTool("java")) LIVO_SKIP() << "java missing (Debian package default-jdk-headless)";
  for (const char* jar : {"/livo_lcmtypes.jar", "/livo_spy.jar"})
    if (!std::filesystem::exists(std::string(LIVO_BINARY_DIR) + jar)) LIVO_SKIP() << jar << " not built (no JDK)";
  const std::string dir = tempDir("spy");
  XServer x(&ns, dir);
  if (!x.ok) LIVO_SKIP() << x.why;
  const SimulatedDemo demo(dir, 6.0);
  ASSERT_TRUE(demo.ok) << demo.error;

  // lcm-spy first (the JVM takes a few seconds): the processes' idle exits start with them.
  const std::string png = dir + "/spy.png", spy_out = dir + "/spy.txt";
  Child spy(ns.exec(x.withDisplay({"env", "LIVO_BUILD=" + std::string(LIVO_BINARY_DIR),
                                   std::string(LIVO_SOURCE_DIR) + "/scripts/livo-spy", "--lcm-url", kUrl,
                                   "--print-table", "1", "--screenshot", png})),
            spy_out);
  // lcm-spy is up once it printed its first table.
  ASSERT_TRUE(waitUntil([&] { return readFile(spy_out).find("# lcm-spy channels at") != std::string::npos; }, 60))
      << readFile(spy_out) << x.report();
  FourProcesses suite(ns, demo.rig, dir);
  auto player = suite.play(demo.log);
  const bool listed = waitUntil([&] { return allListed(lastTable(readFile(spy_out))); }, 90);
  // One more table, so that the rates cover whole seconds of traffic, and the window written after it.
  const auto tables = [&] {
    const std::string out = readFile(spy_out);
    std::size_t n = 0;
    for (auto at = out.find("# lcm-spy channels at"); at != std::string::npos; at = out.find("# lcm-spy channels at", at + 1)) ++n;
    const auto shot = out.rfind("# window written to"), table = out.rfind("# lcm-spy channels at");
    return std::make_pair(n, shot != std::string::npos && table != std::string::npos && shot > table);
  };
  const std::size_t seen = tables().first;
  waitUntil([&] { const auto t = tables(); return t.first > seen && t.second; }, 10);
  const std::string spy_log = readFile(spy_out);
  spy.signal(SIGTERM);
  spy.wait(20);
  EXPECT_EQ(player->wait(120), 0) << readFile(suite.log("player"));
  suite.finish();

  std::cout << spy_log.substr(0, spy_log.find("# lcm-spy channels at")) << "last table:\n"
            << spy_log.substr(spy_log.rfind("# lcm-spy channels at"));
  EXPECT_NE(spy_log.find("receive buffer"), std::string::npos) << "livo-spy sets the socket's buffer";
  const auto table = lastTable(spy_log);
  EXPECT_TRUE(listed) << spy_log;
  for (const auto& c : kChannels) {
    const auto it = table.find(c);
    ASSERT_NE(it, table.end()) << c << " missing from lcm-spy's channel list\n" << spy_log;
    EXPECT_EQ(it->second.type.rfind("??", 0), std::string::npos) << c << ": type not decoded: " << it->second.type;
  }
  std::cout << "LIVO_LIDAR: " << table.at("LIVO_LIDAR").count << " messages, " << table.at("LIVO_LIDAR").hz
            << " Hz, largest " << table.at("LIVO_LIDAR").largest << "\n";
  if (std::filesystem::exists(png)) {
    const std::string kept = std::string(LIVO_BINARY_DIR) + "/spy-screenshot.png";
    std::filesystem::copy_file(png, kept, std::filesystem::copy_options::overwrite_existing);
    std::cout << "screenshot: " << kept << "\n";
  }
}
