// The process suite as processes: the built livo-preprocess and livo-exporter binaries fed by
// lcm-logplayer inside a private network namespace (no traffic leaves its loopback device; skipped when
// not root or without `ip netns`), their command-line errors, and procman/run-local (starts a group of
// a .pmd, restarts a killed command, stops everything on SIGTERM; resolves livo.pmd's commands), and the
// command line every process shares (--help, --version, exit codes, --print-config).
// livo-test-bins: livo-preprocess livo-exporter livo-estimator livo-mapserver livo-sim
#include "livo/cli/command_line.hpp"
#include "livo/eval/tum.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/log.hpp"

#include "process_test_files.hpp"
#include "process_test_streams.hpp"
#include "process_test_children.hpp"
#include "process_test_suite.hpp"

#include <octomap/OcTree.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

using namespace livo;
using test::countLines;
using test::readFile;
using test::tempDir;
using test::Child;
using test::Netns;
using test::haveTool;
using test::waitUntil;
using test::kBin;
using test::kUrl;

namespace {

/// Whether `path` says `text` within `deadline_s` seconds.
bool saysWithin(const std::string& path, const std::string& text, double deadline_s) {
  return waitUntil([&] { return readFile(path).find(text) != std::string::npos; }, deadline_s);
}

/// Complete events in an LCM log that may still be written to.
std::size_t completeEvents(const std::string& path) {
  std::size_t n = 0;
  try {
    LogReader reader(path);
    LogEvent ev;
    while (reader.next(ev)) ++n;
  } catch (const std::exception&) {  // a partly written last event, or no file yet
  }
  return n;
}

}  // namespace
namespace fs = std::filesystem;

// ---------------------------------------------------------------- command line of the binaries

TEST(ProcessBinaries, HelpAndErrorsNameTheProblem) {
  const std::string dir = tempDir("cli");
  auto run = [&](const std::string& cmd) {
    const int rc = std::system((cmd + " > " + dir + "/out.txt 2>&1").c_str());
    return std::make_pair(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, readFile(dir + "/out.txt"));
  };
  auto [rc, out] = run(kBin + "/livo-preprocess --help");
  EXPECT_EQ(rc, 0);
  EXPECT_NE(out.find("--lcm-url URL"), std::string::npos) << out;
  std::tie(rc, out) = run(kBin + "/livo-exporter --config x.yaml");
  EXPECT_EQ(rc, 2);
  EXPECT_NE(out.find("--out is required"), std::string::npos) << out;
  std::ofstream(dir + "/typo.yaml") << "preprocess:\n  wait_timout_s: 1.0\n";
  std::tie(rc, out) = run(kBin + "/livo-preprocess --config " + dir + "/typo.yaml --lcm-url memq://");
  EXPECT_EQ(rc, 2);
  EXPECT_NE(out.find("preprocess.wait_timout_s: unknown key"), std::string::npos) << out;
  std::ofstream(dir + "/bad.yaml") << "exporter:\n  octomap_resolution_m: 0\n";
  std::tie(rc, out) = run(kBin + "/livo-exporter --config " + dir + "/bad.yaml --out " + dir + "/o --lcm-url memq://");
  EXPECT_EQ(rc, 2);
  EXPECT_NE(out.find("exporter.octomap_resolution_m"), std::string::npos) << out;
  std::tie(rc, out) = run(kBin + "/livo-preprocess --config " + dir + "/bad.yaml --lcm-url 'bogus://'");
  EXPECT_EQ(rc, 1);
  EXPECT_NE(out.find("cannot open LCM URL 'bogus://'"), std::string::npos) << out;
}

namespace {

struct Ran {
  int rc = -1;
  std::string out, err;
};

/// Runs `cmd` with stdout and stderr into files of `dir`.
Ran runSplit(const std::string& dir, const std::string& cmd) {
  const int rc = std::system((cmd + " > " + dir + "/stdout.txt 2> " + dir + "/stderr.txt").c_str());
  return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, readFile(dir + "/stdout.txt"), readFile(dir + "/stderr.txt")};
}

const char* const kProcesses[] = {"livo-preprocess", "livo-estimator", "livo-mapserver", "livo-exporter"};

}  // namespace

TEST(ProcessBinaries, HelpVersionAndUsageErrorsShareOneCommandLine) {
  const std::string dir = tempDir("cli_common");
  for (const std::string p : kProcesses) {
    SCOPED_TRACE(p);
    Ran r = runSplit(dir, kBin + "/" + p + " --help");
    EXPECT_EQ(r.rc, 0);
    for (const char* s : {"usage: ", "--config CFG.yaml", "--print-config", "--version", "[default: 0 s]",
                          "exit status: 0 ok, 1 run-time error, 2 usage or configuration error"})
      EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
    r = runSplit(dir, kBin + "/" + p + " --version");
    EXPECT_EQ(r.rc, 0);
    EXPECT_EQ(r.out, p + " " + livo::projectVersion() + "\n");
    r = runSplit(dir, kBin + "/" + p + " --config x.yaml --idle-exit 5x");
    EXPECT_EQ(r.rc, 2);
    EXPECT_EQ(r.err, p + ": --idle-exit: expected a number >= 0, got '5x'\ntry '" + p + " --help'\n");
    EXPECT_TRUE(r.out.empty()) << r.out;
    r = runSplit(dir, kBin + "/" + p + " --config x.yaml --bogus");
    EXPECT_EQ(r.rc, 2);
    EXPECT_EQ(r.err, p + ": unknown option '--bogus'\ntry '" + p + " --help'\n");
    r = runSplit(dir, kBin + "/" + p + " --config " + dir + "/missing.yaml --print-config");
    EXPECT_EQ(r.rc, 2);
    EXPECT_NE(r.err.find("missing.yaml: cannot open config file"), std::string::npos) << r.err;
  }
  Ran r = runSplit(dir, kBin + "/livo-estimator --config x.yaml --visual-mode sometimes");
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err.substr(0, r.err.find('\n')),
            "livo-estimator: --visual-mode: expected one of adaptive|all|off, got 'sometimes'");
}

TEST(ProcessBinaries, PrintConfigLoadsBackAndIsAFixedPoint) {
  // Every shipped rig config: the printed configuration is YAML that each process accepts as its config,
  // and printing the printed file gives the same text again (same keys, same values, same defaults).
  const std::string dir = tempDir("print_config");
  std::vector<std::string> configs;
  for (const auto& e : fs::directory_iterator(std::string(LIVO_SOURCE_DIR) + "/config"))
    if (e.path().extension() == ".yaml") configs.push_back(e.path().string());
  ASSERT_GE(configs.size(), 5u);
  for (const std::string p : kProcesses) {
    for (const std::string& cfg : configs) {
      SCOPED_TRACE(p + " " + cfg);
      const std::string extra = p == "livo-estimator" ? " --visual-mode all" : "";
      const Ran first = runSplit(dir, kBin + "/" + p + " --config " + cfg + extra + " --print-config");
      ASSERT_EQ(first.rc, 0) << first.err;
      EXPECT_EQ(first.out.rfind("# Effective configuration of " + p, 0), 0u) << first.out;
      EXPECT_NE(first.out.find("channels:\n"), std::string::npos) << first.out;
      std::ofstream(dir + "/printed.yaml") << first.out;
      const Ran again = runSplit(dir, kBin + "/" + p + " --config " + dir + "/printed.yaml" + extra + " --print-config");
      ASSERT_EQ(again.rc, 0) << again.err;
      EXPECT_EQ(again.out, first.out);
    }
  }
  const std::string avia = std::string(LIVO_SOURCE_DIR) + "/config/avia.yaml";
  Ran r = runSplit(dir, kBin + "/livo-estimator --config " + avia + " --visual-mode off --print-config");
  EXPECT_NE(r.out.find("# Command-line settings, not config keys: --visual-mode off\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\nestimator:\n  map_timeout_ms: 250.0\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("  tau_translation_m: "), std::string::npos) << "a default filled in\n" << r.out;
  r = runSplit(dir, kBin + "/livo-mapserver --config " + avia + " --memory-cap-mb 12.5 --print-config");
  EXPECT_NE(r.out.find("  memory_cap_mb: 12.5\n"), std::string::npos) << "the command line overrides the key\n" << r.out;
  r = runSplit(dir, kBin + "/livo-exporter --config " + avia + " --print-config");  // --out is not needed
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("exporter:\n"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("estimator:"), std::string::npos) << "only the keys the exporter reads\n" << r.out;
}

// ---------------------------------------------------------------- processes in a network namespace

/// 2 s of sensor messages as an LCM log (dir/in.lcm) and a rig for them (dir/rig.yaml).
test::SensorStream writeSensorLog(const std::string& dir) {
  test::SensorStream stream = test::makeSensorStream(2.0);
  LogWriter w(dir + "/in.lcm");
  for (const auto& ev : stream.events) w.write(ev.channel, ev.send_utime, ev.bytes.data(), ev.bytes.size());
  std::ofstream(dir + "/rig.yaml") << "imu: {rate_hz: 200.0}\nlidar: {blind_m: 0.5}\ncamera: {enabled: true}\n";
  return stream;
}

/// The estimator's outputs for 20 frames (19 poses) as an LCM log.
void writeEstimatorLog(const std::string& path) {
  LogWriter w(path);
  for (const auto& f : test::makeEstimatorFrames(20)) {
    w.write("LIVO_ODOMETRY", f.odom.utime, toMsg(f.odom));
    w.write("LIVO_REGISTERED_SCAN", f.odom.utime + 10, toMsg(f.scan));
    w.write("LIVO_ESTIMATOR_STATS", f.odom.utime + 20, toMsg(f.stats));
    if (f.has_map_stats) w.write("LIVO_MAP_STATS", f.odom.utime + 30, toMsg(f.map_stats));
  }
}

/// livo-exporter in `ns` writing to dir/out, its log dir/exporter.txt.
Child startExporter(const Netns& ns, const std::string& dir) {
  std::ofstream(dir + "/rig.yaml") << "exporter: {map_voxel_m: 0.05, octomap_resolution_m: 0.1}\n";
  return Child(ns.exec({kBin + "/livo-exporter", "--config", dir + "/rig.yaml", "--lcm-url", kUrl, "--out", dir + "/out"}),
               dir + "/exporter.txt");
}

TEST(ProcessNetns, PreprocessTurnsAReplayedLogIntoFrames) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!haveTool("lcm-logplayer") || !haveTool("lcm-logger")) LIVO_SKIP() << "lcm-logplayer / lcm-logger missing";
  const std::string dir = tempDir("preprocess");
  const test::SensorStream stream = writeSensorLog(dir);

  Child logger(ns.exec({"lcm-logger", "-f", "--lcm-url=" + kUrl, "-c", "LIVO_FRAME", dir + "/out.lcm"}),
               dir + "/logger.txt");
  Child pre(ns.exec({kBin + "/livo-preprocess", "--config", dir + "/rig.yaml", "--lcm-url", kUrl, "--idle-exit",
                     "2", "--report-interval", "1"}),
            dir + "/preprocess.txt");
  // Started before the preprocessor, the logger has subscribed by the time the preprocessor says it has.
  ASSERT_TRUE(saysWithin(dir + "/logger.txt", "Opening log file", 60)) << readFile(dir + "/logger.txt");
  ASSERT_TRUE(saysWithin(dir + "/preprocess.txt", " on " + kUrl, 60)) << readFile(dir + "/preprocess.txt");
  Child player(ns.exec({"lcm-logplayer", "--lcm-url=" + kUrl, "--speed=2", dir + "/in.lcm"}), dir + "/player.txt");
  EXPECT_EQ(player.wait(60), 0) << readFile(dir + "/player.txt");
  EXPECT_EQ(pre.wait(60), 0) << readFile(dir + "/preprocess.txt");  // --idle-exit: flushes, then exits
  // The logger flushes every 100 ms: wait until the 21 frames are on disk (or the deadline).
  waitUntil([&] { return completeEvents(dir + "/out.lcm") >= 21; }, 30);
  logger.signal(SIGINT);
  logger.wait(30);

  const std::string out = readFile(dir + "/preprocess.txt");
  EXPECT_NE(out.find("frames published 21 (20 with image"), std::string::npos) << out;
  EXPECT_NE(out.find("no message for --idle-exit seconds"), std::string::npos) << out;
  EXPECT_NE(out.find("livo-preprocess: t "), std::string::npos) << out;  // periodic counters

  std::set<Utime> expected(stream.image_times.begin(), stream.image_times.end());
  LogReader reader(dir + "/out.lcm");
  LogEvent ev;
  std::vector<Utime> got;
  while (reader.next(ev)) {
    ASSERT_EQ(ev.channel, "LIVO_FRAME");
    livo::frame_t m;
    Frame f;
    ASSERT_TRUE(decode(ev.data.data(), ev.data.size(), m) && fromMsg(m, f));
    if (f.has_image) {
      EXPECT_TRUE(expected.count(f.utime)) << f.utime;
      EXPECT_EQ(f.image.format, PixelFormat::Gray8);
    }
    got.push_back(f.utime);
  }
  EXPECT_EQ(got.size(), 21u);
  EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
}

// Drain on stop: SIGINT as soon as the player has sent the last message (no idle wait): what the
// preprocessor had received is handled and the frames it completes are published before it exits.
TEST(ProcessNetns, PreprocessDrainsOnSigint) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!haveTool("lcm-logplayer") || !haveTool("lcm-logger")) LIVO_SKIP() << "lcm-logplayer / lcm-logger missing";
  const std::string dir = tempDir("preprocess_drain");
  const test::SensorStream stream = writeSensorLog(dir);
  Child logger(ns.exec({"lcm-logger", "-f", "--lcm-url=" + kUrl, "-c", "LIVO_FRAME", dir + "/out.lcm"}),
               dir + "/logger.txt");
  Child pre(ns.exec({kBin + "/livo-preprocess", "--config", dir + "/rig.yaml", "--lcm-url", kUrl}),
            dir + "/preprocess.txt");
  ASSERT_TRUE(saysWithin(dir + "/logger.txt", "Opening log file", 60)) << readFile(dir + "/logger.txt");
  ASSERT_TRUE(saysWithin(dir + "/preprocess.txt", " on " + kUrl, 60)) << readFile(dir + "/preprocess.txt");
  Child player(ns.exec({"lcm-logplayer", "--lcm-url=" + kUrl, "--speed=4", dir + "/in.lcm"}), dir + "/player.txt");
  EXPECT_EQ(player.wait(60), 0) << readFile(dir + "/player.txt");
  pre.signal(SIGINT);
  EXPECT_EQ(pre.wait(60), 0) << readFile(dir + "/preprocess.txt");
  // The frames arrive in a burst at the stop and lcm-logger writes the last ones out only when it
  // closes: a short wait for the file, then the count after the logger's exit decides.
  waitUntil([&] { return completeEvents(dir + "/out.lcm") >= 21; }, 5);
  logger.signal(SIGINT);
  logger.wait(30);
  const std::string out = readFile(dir + "/preprocess.txt");
  EXPECT_NE(out.find("Interrupt"), std::string::npos) << out;
  // Every message sent was received and every frame published: the same 21 frames as with --idle-exit.
  EXPECT_NE(out.find("frames published 21 (20 with image"), std::string::npos) << out;
  EXPECT_EQ(completeEvents(dir + "/out.lcm"), 21u);
}

/// The number after the last `key` in `text` (the summary comes last; -1 when absent).
long numberAfter(const std::string& text, const std::string& key) {
  const auto i = text.rfind(key);
  return i == std::string::npos ? -1 : std::strtol(text.c_str() + i + key.size(), nullptr, 10);
}

// Drain on stop, estimator and map server: the estimator is stopped the moment the preprocessor (itself
// drained on SIGINT) has published its frames of 3 s of the demo, most of them in one burst at its stop:
// every frame the estimator received is processed with the map server's answers, and its odometry
// published, before it exits. Then the estimator's map updates, replayed at 16x into a new map server
// stopped the moment the player is done: every update is applied before the map file is saved.
TEST(ProcessNetns, EstimatorAndMapServerDrainOnSigint) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!haveTool("lcm-logplayer") || !haveTool("lcm-logger")) LIVO_SKIP() << "lcm-logplayer / lcm-logger missing";
  const std::string dir = tempDir("estimator_drain");
  const test::SimulatedDemo demo(dir, 3.0);
  ASSERT_TRUE(demo.ok) << demo.error;
  Child logger(ns.exec({"lcm-logger", "-f", "--lcm-url=" + kUrl, "-c", "LIVO_ODOMETRY", dir + "/odom.lcm"}),
               dir + "/logger.txt");
  Child update_logger(ns.exec({"lcm-logger", "-f", "--lcm-url=" + kUrl, "-c", "LIVO_MAP_UPDATE", dir + "/updates.lcm"}),
                      dir + "/update_logger.txt");
  Child map(ns.exec({kBin + "/livo-mapserver", "--config", demo.rig, "--lcm-url", kUrl}), dir + "/map.txt");
  Child est(ns.exec({kBin + "/livo-estimator", "--config", demo.rig, "--lcm-url", kUrl}), dir + "/estimator.txt");
  Child pre(ns.exec({kBin + "/livo-preprocess", "--config", demo.rig, "--lcm-url", kUrl}), dir + "/preprocess.txt");
  for (const char* name : {"logger", "update_logger"})
    ASSERT_TRUE(saysWithin(dir + "/" + name + ".txt", "Opening log file", 60)) << readFile(dir + "/" + name + ".txt");
  for (const char* name : {"map", "estimator", "preprocess"})
    ASSERT_TRUE(saysWithin(dir + "/" + name + ".txt", " on " + kUrl, 60)) << readFile(dir + "/" + name + ".txt");
  Child player(ns.exec({"lcm-logplayer", "--lcm-url=" + kUrl, "--speed=4", demo.log}), dir + "/player.txt");
  EXPECT_EQ(player.wait(60), 0) << readFile(dir + "/player.txt");
  pre.signal(SIGINT);
  EXPECT_EQ(pre.wait(60), 0) << readFile(dir + "/preprocess.txt");
  est.signal(SIGINT);
  EXPECT_EQ(est.wait(60), 0) << readFile(dir + "/estimator.txt");
  const std::string out = readFile(dir + "/estimator.txt");
  const long published = numberAfter(readFile(dir + "/preprocess.txt"), "frames published ");
  const long odometry = numberAfter(out, "), odometry ");
  ASSERT_GE(published, 25) << readFile(dir + "/preprocess.txt");  // 3 s at 10 Hz
  std::cout << "estimator drain: " << published << " frames published, estimator: "
            << out.substr(out.rfind("frames "), out.find('\n', out.rfind("frames ")) - out.rfind("frames ")) << "\n";
  waitUntil([&] { return long(completeEvents(dir + "/odom.lcm")) >= odometry; }, 5);
  logger.signal(SIGINT);
  logger.wait(30);
  update_logger.signal(SIGINT);
  update_logger.wait(30);
  map.signal(SIGINT);
  EXPECT_EQ(map.wait(60), 0) << readFile(dir + "/map.txt");
  EXPECT_NE(out.find("Interrupt"), std::string::npos) << out;
  // Every frame published was processed or shed by the overload policy (the burst at the
  // preprocessor's stop may queue more than estimator.shed_frames_queued; shed frames are counted and
  // their IMU kept), none dropped from the queue; one odometry message per processed frame once
  // initialised (the demo stands still for its first second), each of them on the bus.
  const long processed = numberAfter(out, "\nframes "), shed = numberAfter(out, "frames shed ");
  EXPECT_EQ(processed + shed, published) << out;
  EXPECT_EQ(numberAfter(out, "dropped from the queue "), 0) << out;
  EXPECT_GE(odometry, processed - 12) << out;
  EXPECT_GE(processed, 10) << out;
  EXPECT_EQ(long(completeEvents(dir + "/odom.lcm")), odometry);

  const long updates = long(completeEvents(dir + "/updates.lcm"));
  ASSERT_GE(updates, odometry) << "one map update per registered frame";
  Child map2(ns.exec({kBin + "/livo-mapserver", "--config", demo.rig, "--lcm-url", kUrl, "--map-file", dir + "/map.bin"}),
             dir + "/map2.txt");
  ASSERT_TRUE(saysWithin(dir + "/map2.txt", " on " + kUrl, 60)) << readFile(dir + "/map2.txt");
  Child player2(ns.exec({"lcm-logplayer", "--lcm-url=" + kUrl, "--speed=16", dir + "/updates.lcm"}), dir + "/player2.txt");
  EXPECT_EQ(player2.wait(60), 0) << readFile(dir + "/player2.txt");
  map2.signal(SIGINT);
  EXPECT_EQ(map2.wait(60), 0) << readFile(dir + "/map2.txt");
  const std::string map_out = readFile(dir + "/map2.txt");
  std::cout << "map server drain: " << updates << " updates replayed, map server: updates "
            << numberAfter(map_out, "), updates ") << "\n";
  EXPECT_EQ(numberAfter(map_out, "), updates "), updates) << map_out;
  EXPECT_TRUE(std::filesystem::exists(dir + "/map.bin")) << map_out;
}

// Drain on stop: SIGINT as soon as the player is done; the exporter writes all 20 frames.
TEST(ProcessNetns, ExporterDrainsOnSigint) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!haveTool("lcm-logplayer")) LIVO_SKIP() << "lcm-logplayer missing";
  const std::string dir = tempDir("exporter_drain");
  writeEstimatorLog(dir + "/est.lcm");
  Child exporter = startExporter(ns, dir);
  ASSERT_TRUE(saysWithin(dir + "/exporter.txt", " on " + kUrl, 60)) << readFile(dir + "/exporter.txt");
  Child player(ns.exec({"lcm-logplayer", "--lcm-url=" + kUrl, "--speed=8", dir + "/est.lcm"}), dir + "/player.txt");
  EXPECT_EQ(player.wait(60), 0) << readFile(dir + "/player.txt");
  exporter.signal(SIGINT);
  EXPECT_EQ(exporter.wait(60), 0) << readFile(dir + "/exporter.txt");
  const std::string log = readFile(dir + "/exporter.txt");
  EXPECT_NE(log.find("frames 20 (poses 19"), std::string::npos) << log;
  EXPECT_EQ(readTum(dir + "/out/trajectory.tum").size(), 19u);
  EXPECT_EQ(countLines(dir + "/out/frames.csv"), 21u);
}

TEST(ProcessNetns, ExporterWritesItsFilesOnSigint) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!haveTool("lcm-logplayer")) LIVO_SKIP() << "lcm-logplayer missing";
  const std::string dir = tempDir("exporter");
  writeEstimatorLog(dir + "/est.lcm");
  Child exporter = startExporter(ns, dir);
  ASSERT_TRUE(saysWithin(dir + "/exporter.txt", " on " + kUrl, 60)) << readFile(dir + "/exporter.txt");
  Child player(ns.exec({"lcm-logplayer", "--lcm-url=" + kUrl, "--speed=2", dir + "/est.lcm"}), dir + "/player.txt");
  EXPECT_EQ(player.wait(60), 0) << readFile(dir + "/player.txt");
  // Before the stop: the trajectory is on disk already (once the last messages are handled).
  waitUntil([&] { return countLines(dir + "/out/trajectory.tum") >= 20; }, 30);
  EXPECT_EQ(countLines(dir + "/out/trajectory.tum"), 20u);  // '#' header + 19 poses
  exporter.signal(SIGINT);
  EXPECT_EQ(exporter.wait(60), 0) << readFile(dir + "/exporter.txt");
  const std::string log = readFile(dir + "/exporter.txt");
  EXPECT_NE(log.find("Interrupt"), std::string::npos) << log;
  EXPECT_NE(log.find("frames 20 (poses 19"), std::string::npos) << log;

  EXPECT_EQ(readTum(dir + "/out/trajectory.tum").size(), 19u);
  EXPECT_EQ(countLines(dir + "/out/frames.csv"), 21u);
  EXPECT_NE(readFile(dir + "/out/stats.json").find("\"frames\": 20"), std::string::npos);
  // The same health section and frame states as livo-run's (19 poses after one initialising frame).
  const std::string stats = readFile(dir + "/out/stats.json");
  EXPECT_NE(stats.find("\"health\": {\"first_pose_delay_s\""), std::string::npos) << stats;
  const std::string csv = readFile(dir + "/out/frames.csv");
  std::size_t n_init = 0, n_ok = 0;
  for (std::size_t at = 0; (at = csv.find(",initialising,\n", at)) != std::string::npos; ++at) ++n_init;
  for (std::size_t at = 0; (at = csv.find(",ok,\n", at)) != std::string::npos; ++at) ++n_ok;
  EXPECT_EQ(n_init, 1u) << csv;
  EXPECT_EQ(n_ok, 19u) << csv;
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(dir + "/out/map.pcd", cloud), 0);
  EXPECT_GT(cloud.size(), 400u);
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(dir + "/out/map.bt"));
  const octomap::OcTreeNode* n = tree.search(5.0, 0.3, 1.0);
  ASSERT_NE(n, nullptr);
  EXPECT_TRUE(tree.isNodeOccupied(n));
}

// ---------------------------------------------------------------- procman/run-local

TEST(RunLocal, StartsAGroupRestartsACrashedCommandAndStopsAllOnSigterm) {
  if (!haveTool("python3")) LIVO_SKIP() << "python3 missing";
  const std::string dir = tempDir("runlocal");
  // Each command appends its pid to a file, then becomes `sleep` (same pid).
  auto cmd = [&](const std::string& name) {
    return "    cmd \"" + name + "\" {\n        exec = \"bash -c 'echo $$ >> ${DIR}/" + name +
           ".pids; exec sleep 600'\";\n        host = \"localhost\";\n    }\n";
  };
  std::ofstream(dir + "/test.pmd") << "# @default DIR = \"/nonexistent\";\n"
                                   << "group \"dummies\" {\n" << cmd("a") << cmd("b") << "}\n"
                                   << "group \"other\" {\n" << cmd("c") << "}\n";
  Child rl({std::string(LIVO_SOURCE_DIR) + "/procman/run-local", "dummies", "--pmd", dir + "/test.pmd", "--var",
            "DIR=" + dir},
           dir + "/run-local.txt");
  auto waitLines = [&](const std::string& f, std::size_t n) {
    waitUntil([&] { return countLines(f) >= n; }, 30);
    return countLines(f);
  };
  ASSERT_EQ(waitLines(dir + "/a.pids", 1), 1u) << readFile(dir + "/run-local.txt");
  ASSERT_EQ(waitLines(dir + "/b.pids", 1), 1u) << readFile(dir + "/run-local.txt");
  EXPECT_FALSE(fs::exists(dir + "/c.pids"));  // not in the group
  const pid_t a1 = std::stoi(readFile(dir + "/a.pids"));
  ASSERT_EQ(::kill(a1, SIGKILL), 0);
  ASSERT_EQ(waitLines(dir + "/a.pids", 2), 2u) << readFile(dir + "/run-local.txt");  // restarted after 1 s
  EXPECT_EQ(countLines(dir + "/b.pids"), 1u);                                          // b untouched
  rl.signal(SIGTERM);
  EXPECT_EQ(rl.wait(30), 0) << readFile(dir + "/run-local.txt");
  std::ifstream a(dir + "/a.pids"), b(dir + "/b.pids");
  for (std::istream* in : {static_cast<std::istream*>(&a), static_cast<std::istream*>(&b)})
    for (pid_t pid; *in >> pid;) EXPECT_TRUE(::kill(pid, 0) != 0 && errno == ESRCH) << "pid " << pid << " alive";
  const std::string log = readFile(dir + "/run-local.txt");
  EXPECT_NE(log.find("a killed by signal 9"), std::string::npos) << log;
  EXPECT_NE(log.find("all stopped"), std::string::npos) << log;
}

TEST(RunLocal, ResolvesLivoPmdFromTheFileItself) {
  if (!haveTool("python3")) LIVO_SKIP() << "python3 missing";
  const std::string dir = tempDir("runlocal_pmd");
  const std::string rl = std::string(LIVO_SOURCE_DIR) + "/procman/run-local";
  int rc = std::system((rl + " replay --dry-run --var LIVO_BIN=" + kBin + " --var LOG=my.lcm > " + dir +
                        "/cmds.txt 2>&1")
                           .c_str());
  ASSERT_EQ(rc, 0) << readFile(dir + "/cmds.txt");
  const std::string cmds = readFile(dir + "/cmds.txt");
  for (const std::string& needle : std::vector<std::string>{kBin + "/livo-preprocess --config ", kBin + "/livo-estimator --config ", " --memory-cap-mb 512 --map-file ",
        kBin + "/livo-exporter --config ", " --out livo_out", "lcm-logplayer ", " my.lcm",
        "--lcm-url 'udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'"})
    EXPECT_NE(cmds.find(needle), std::string::npos) << needle << "\n" << cmds;
  // With loop closure: livo-loop with its own memory budget, started with the sinks.
  rc = std::system((rl + " replay-loop --dry-run --var LIVO_BIN=" + kBin + " --var LOG=my.lcm > " + dir +
                    "/cmds_loop.txt 2>&1")
                       .c_str());
  ASSERT_EQ(rc, 0) << readFile(dir + "/cmds_loop.txt");
  EXPECT_NE(readFile(dir + "/cmds_loop.txt").find(kBin + "/livo-loop --config "), std::string::npos);
  EXPECT_NE(readFile(dir + "/cmds_loop.txt").find(" --memory-cap-mb 128"), std::string::npos);
  // The binaries this suite builds exist where livo.pmd says.
  EXPECT_TRUE(fs::exists(kBin + "/livo-preprocess"));
  EXPECT_TRUE(fs::exists(kBin + "/livo-exporter"));
  // Without LOG the replay script names the missing variable; a bad file names its line.
  rc = std::system((rl + " replay --dry-run > " + dir + "/err.txt 2>&1").c_str());
  EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2) << "a usage error, not a crash: status " << rc;
  EXPECT_NE(readFile(dir + "/err.txt").find("variable LOG is not set"), std::string::npos) << readFile(dir + "/err.txt");
  std::ofstream(dir + "/bad.pmd") << "cmd \"x\" {\n  exec = \"true\";\n  hots = \"localhost\";\n}\n";
  rc = std::system((rl + " x --pmd " + dir + "/bad.pmd > " + dir + "/err2.txt 2>&1").c_str());
  EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2) << "a usage error, not a crash: status " << rc;
  EXPECT_NE(readFile(dir + "/err2.txt").find("bad.pmd:3: unknown attribute 'hots'"), std::string::npos)
      << readFile(dir + "/err2.txt");
}

TEST(RunLocal, ReplayScriptOfLivoPmdRunsTheChainAndStopsIt) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!haveTool("python3") || !haveTool("lcm-logplayer")) LIVO_SKIP() << "python3 or lcm-logplayer missing";
  const std::string dir = tempDir("runlocal_replay");
  // The estimator and the map server are stand-ins that exit 0 on SIGINT; the others are the real ones.
  fs::create_directories(dir + "/bin");
  fs::create_symlink(kBin + "/livo-preprocess", dir + "/bin/livo-preprocess");
  fs::create_symlink(kBin + "/livo-exporter", dir + "/bin/livo-exporter");
  std::ofstream(dir + "/bin/stand-in") << "#!/bin/bash\ntrap 'echo stopped; exit 0' INT TERM\n"
                                          "echo \"stand-in $(basename \"$0\") $*\"\nwhile true; do sleep 0.1; done\n";
  fs::permissions(dir + "/bin/stand-in", fs::perms::owner_all);
  fs::create_symlink("stand-in", dir + "/bin/livo-estimator");
  fs::create_symlink("stand-in", dir + "/bin/livo-mapserver");
  const test::SensorStream stream = writeSensorLog(dir);
  Child rl(ns.exec({std::string(LIVO_SOURCE_DIR) + "/procman/run-local", "replay", "--var", "LOG=" + dir + "/in.lcm",
                    "--var", "LIVO_BIN=" + dir + "/bin", "--var", "LIVO_CONFIG=" + dir + "/rig.yaml", "--var",
                    "LIVO_OUT=" + dir + "/out", "--var", "LIVO_SPEED=2", "--var", "LIVO_LCM_URL=" + kUrl}),
           dir + "/run-local.txt");
  EXPECT_EQ(rl.wait(120), 0) << readFile(dir + "/run-local.txt");
  const std::string log = readFile(dir + "/run-local.txt");
  EXPECT_LT(log.find("started exporter"), log.find("started preprocess")) << log;  // sinks first
  EXPECT_LT(log.find("started preprocess"), log.find("started logplayer")) << log;
  EXPECT_NE(log.find("[preprocess] frames published 21 (20 with image"), std::string::npos) << log;
  EXPECT_NE(log.find("[estimator] stand-in livo-estimator --config"), std::string::npos) << log;
  EXPECT_NE(log.find("--memory-cap-mb 512 --map-file " + dir + "/out/map_server.map"), std::string::npos) << log;
  EXPECT_NE(log.find("[exporter] outputs in " + dir + "/out"), std::string::npos) << log;
  EXPECT_NE(log.find("nothing left running"), std::string::npos) << log;
  EXPECT_EQ(log.find("done."), std::string::npos) << log;  // no OctoMap chatter
  for (const char* f : {"trajectory.tum", "frames.csv", "stats.json", "map.pcd", "map.bt"})
    EXPECT_TRUE(fs::exists(dir + "/out/" + f)) << f;
}
