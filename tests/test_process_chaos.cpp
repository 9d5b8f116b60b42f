// Kill any process, keep the run: the room scenario replayed through the suite's four processes
// (livo-preprocess, livo-estimator, livo-mapserver, livo-exporter) in a private network namespace,
// once undisturbed and once per process with that process killed by SIGKILL at a random time (fixed
// seeds) and started again 1 s later, as run-local would. Each disturbed run must export a
// trajectory in strictly increasing time (no duplicate, no line out of order: the restarted exporter
// continues its files), without a gap over 1.5 s around the kill, at most 1.5x the undisturbed ATE
// (the restarted estimator continues from the map server's last filter state in the same world frame).
// Skipped when not root or without `ip netns` / lcm-logplayer.
// livo-test-whole (the simulated log and the undisturbed run are shared by its tests)
// livo-test-bins: livo-sim livo-preprocess livo-estimator livo-mapserver livo-exporter
// livo-test-deps: livo_eval
#include "livo/eval/evaluate.hpp"
#include "livo/eval/tum.hpp"

#include "process_test_suite.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <string>

using namespace livo;
using test::Child;
using test::kBin;
using test::kUrl;
using test::Netns;
using test::readFile;
using test::waitUntil;

namespace {

constexpr double kLogSeconds = 15.0;  // of the room scenario

using RoomLog = test::SimulatedScenario;

const RoomLog& roomLog() {
  static const RoomLog r(test::tempDir("chaos"), "room", kLogSeconds);
  return r;
}

/// The four processes, each startable again under the same command line (a new log file per start).
struct Suite {
  const Netns& ns;
  std::string rig, out;
  std::map<std::string, std::unique_ptr<Child>> procs;
  std::map<std::string, int> starts;

  Suite(const Netns& n, const std::string& rig_path, const std::string& out_dir) : ns(n), rig(rig_path), out(out_dir) {
    std::filesystem::create_directories(out);
    for (const char* name : {"mapserver", "exporter", "estimator", "preprocess"}) start(name);
  }
  std::vector<std::string> argv(const std::string& name) const {
    if (name == "mapserver")
      return {kBin + "/livo-mapserver", "--config", rig, "--lcm-url", kUrl, "--map-file", out + "/map.bin"};
    if (name == "estimator") return {kBin + "/livo-estimator", "--config", rig, "--lcm-url", kUrl, "--idle-exit", "4"};
    if (name == "preprocess") return {kBin + "/livo-preprocess", "--config", rig, "--lcm-url", kUrl, "--idle-exit", "2"};
    return {kBin + "/livo-exporter", "--config", rig, "--lcm-url", kUrl, "--out", out + "/export", "--idle-exit", "6"};
  }
  std::string log(const std::string& name, int start) const { return out + "/" + name + std::to_string(start) + ".txt"; }
  std::string lastLog(const std::string& name) const { return log(name, starts.at(name)); }
  void start(const std::string& name) {
    const int k = ++starts[name];
    procs[name] = std::make_unique<Child>(ns.exec(argv(name)), log(name, k));
    // A process prints "... on URL" once it has subscribed.
    EXPECT_TRUE(waitUntil([&] { return readFile(log(name, k)).find(" on " + kUrl) != std::string::npos; }, 60))
        << log(name, k) << ":\n" << readFile(log(name, k));
  }
  /// SIGKILL, then a new start after `down_s` (run-local restarts a crashed command after 1 s).
  void killAndRestart(const std::string& name, double down_s) {
    procs[name]->signal(SIGKILL);
    EXPECT_EQ(procs[name]->wait(10), -SIGKILL);
    test::sleepS(down_s);  // the outage the run must survive, not a wait for anything
    start(name);
  }
  std::size_t poses() const { return test::countLines(out + "/export/trajectory.tum"); }
  std::unique_ptr<Child> play(const std::string& lcm_log) const {
    return std::make_unique<Child>(ns.exec({"lcm-logplayer", "--lcm-url=" + kUrl, "--speed=1", lcm_log}),
                                   out + "/player.txt");
  }
  /// The chain's idle exits, then SIGINT to the map server.
  void finish() {
    for (const char* name : {"preprocess", "estimator", "exporter"})
      EXPECT_EQ(procs[name]->wait(120), 0) << readFile(lastLog(name));
    procs["mapserver"]->signal(SIGINT);
    EXPECT_EQ(procs["mapserver"]->wait(60), 0) << readFile(lastLog("mapserver"));
  }
};

struct RunResult {
  bool ok = false;
  std::string error;
  Trajectory traj;
  double ate_m = 0, longest_gap_s = 0;
  double kill_t = -1;  ///< trajectory time of the last pose exported before the kill
  std::string logs;
};

/// Replays the room; with `victim`, kills it once the exporter has written `kill_after_poses` poses.
RunResult run(const Netns& ns, const std::string& tag, const std::string& victim, std::size_t kill_after_poses) {
  const RoomLog& room = roomLog();
  RunResult r;
  Suite suite(ns, room.rig, room.dir + "/" + tag);
  auto player = suite.play(room.log);
  if (!victim.empty()) {
    if (!waitUntil([&] { return suite.poses() >= kill_after_poses + 1; }, 120)) {  // + the header line
      r.error = "never reached " + std::to_string(kill_after_poses) + " poses";
      return r;
    }
    r.kill_t = readTum(suite.out + "/export/trajectory.tum").back().t;
    suite.killAndRestart(victim, 1.0);
  }
  EXPECT_EQ(player->wait(120), 0) << readFile(suite.out + "/player.txt");
  suite.finish();
  for (const auto& [name, n] : suite.starts)
    for (int k = 1; k <= n; ++k) r.logs += "== " + suite.log(name, k) + "\n" + readFile(suite.log(name, k));
  try {
    r.traj = readTum(suite.out + "/export/trajectory.tum");  // throws on a time not after the previous one
  } catch (const std::exception& e) {
    r.error = e.what();
    return r;
  }
  for (std::size_t i = 1; i < r.traj.size(); ++i)
    r.longest_gap_s = std::max(r.longest_gap_s, r.traj[i].t - r.traj[i - 1].t);
  r.ate_m = evaluate(readTum(room.gt), r.traj, EvalConfig{}).ate.translation_m.rmse;
  r.ok = true;
  return r;
}

const RunResult& undisturbed(const Netns& ns) {
  static RunResult r = run(ns, "undisturbed", "", 0);
  return r;
}

/// Kills `victim` at a pose count drawn with `seed` (between 4 s and 11 s of the 15 s log at 10 Hz).
void chaos(const std::string& victim, unsigned seed) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!test::haveTool("lcm-logplayer")) LIVO_SKIP() << "lcm-logplayer missing";
  const RoomLog& room = roomLog();
  ASSERT_TRUE(room.ok) << room.error;
  const RunResult& base = undisturbed(ns);
  ASSERT_TRUE(base.ok) << base.error << "\n" << base.logs;
  std::mt19937 rng(seed);
  const auto at = std::uniform_int_distribution<std::size_t>(40, 110)(rng);
  const RunResult r = run(ns, "kill_" + victim, victim, at);
  ASSERT_TRUE(r.ok) << r.error << "\n" << r.logs;
  std::cout << std::fixed << std::setprecision(3) << victim << " killed after " << at << " poses (t " << r.kill_t << " s): " << r.traj.size()
            << " poses, longest gap " << r.longest_gap_s << " s, ATE " << r.ate_m * 100 << " cm; undisturbed "
            << base.traj.size() << " poses, longest gap " << base.longest_gap_s << " s, ATE " << base.ate_m * 100
            << " cm\n";
  EXPECT_LE(r.longest_gap_s, 1.5) << r.logs;
  EXPECT_LE(r.ate_m, 1.5 * base.ate_m) << r.logs;
  EXPECT_GT(r.traj.back().t, r.kill_t + 2.0) << "poses continue after the kill\n" << r.logs;
}

}  // namespace

TEST(ChaosNetns, EstimatorKilledResumesFromTheMapServersState) {
  chaos("estimator", 1);
  const std::string logs = readFile(roomLog().dir + "/kill_estimator/estimator2.txt");
  const std::size_t at = logs.find("resumed from the map server's last filter state");
  ASSERT_NE(at, std::string::npos) << logs;
  std::cout << logs.substr(logs.rfind('\n', at) + 1, logs.find('\n', at) - logs.rfind('\n', at)) << "\n";
}

TEST(ChaosNetns, PreprocessKilled) { chaos("preprocess", 2); }

TEST(ChaosNetns, MapServerKilled) { chaos("mapserver", 3); }

TEST(ChaosNetns, ExporterKilledContinuesItsFiles) {
  chaos("exporter", 4);
  const std::string logs = readFile(roomLog().dir + "/kill_exporter/exporter2.txt");
  EXPECT_NE(logs.find("livo-exporter: continuing "), std::string::npos) << logs;
}

TEST(ChaosNetns, AnEstimatorStartedWithAnotherRigExitsNamingTheKey) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  const RoomLog& room = roomLog();
  ASSERT_TRUE(room.ok) << room.error;
  const std::string dir = room.dir + "/other_rig";
  std::filesystem::create_directories(dir);
  // The same rig with the LiDAR 5 cm further forward (a recalibration nobody told the map server about).
  std::string text = readFile(room.rig);
  const std::string from = "T_imu_lidar: [0.05,", to = "T_imu_lidar: [0.1,";
  ASSERT_NE(text.find(from), std::string::npos) << text;
  text.replace(text.find(from), from.size(), to);
  std::ofstream(dir + "/rig.yaml") << text;
  Child mapserver(ns.exec({kBin + "/livo-mapserver", "--config", room.rig, "--lcm-url", kUrl}), dir + "/mapserver.txt");
  ASSERT_TRUE(waitUntil([&] { return readFile(dir + "/mapserver.txt").find(" on " + kUrl) != std::string::npos; }, 60));
  Child estimator(ns.exec({kBin + "/livo-estimator", "--config", dir + "/rig.yaml", "--lcm-url", kUrl, "--idle-exit", "20"}),
                  dir + "/estimator.txt");
  EXPECT_EQ(estimator.wait(30), 1) << "a run error, at once (not at --idle-exit)\n" << readFile(dir + "/estimator.txt");
  const std::string log = readFile(dir + "/estimator.txt");
  EXPECT_NE(log.find("livo-estimator: error: the running map server's config differs from this one: lidar.T_imu_lidar: "
                     "[0.1, 0.0, 0.05, 0.0, 0.0, 0.0, 1.0] here, [0.05, 0.0, 0.05, 0.0, 0.0, 0.0, 1.0] there"),
            std::string::npos)
      << log;
  mapserver.signal(SIGINT);
  EXPECT_EQ(mapserver.wait(30), 0);
  EXPECT_NE(readFile(dir + "/mapserver.txt").find("an estimator with another config asked to resume"), std::string::npos);
}
