// The four processes of the suite (livo-preprocess, livo-estimator, livo-mapserver, livo-exporter) fed
// by lcm-logplayer inside a private network namespace (no traffic leaves its loopback device; skipped
// when not root or without `ip netns`): the exported trajectory against livo-run on the same log and
// against the simulator's ground truth, and a map server killed mid-run and restarted; with livo-loop
// beside them, the exported map-frame trajectory against livo-run --loop's.
// livo-test-whole (the simulated log is shared by its tests)
// livo-test-bins: livo-sim livo-run livo-preprocess livo-estimator livo-mapserver livo-exporter livo-loop
// livo-test-deps: livo_eval
#include "livo/eval/evaluate.hpp"
#include "livo/eval/tum.hpp"

#include "process_test_children.hpp"
#include "process_test_files.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

using namespace livo;
using test::Child;
using test::kBin;
using test::kUrl;
using test::Netns;
using test::readFile;
using test::waitUntil;

namespace {

/// The demo scenario simulated once, and livo-run on it.
struct DemoLog {
  std::string dir, log, gt, rig;
  Trajectory single;
  bool ok = false;
  std::string error;
};

const DemoLog& demoLog() {
  static DemoLog d = [] {
    DemoLog out;
    out.dir = test::tempDir("suite");
    out.log = out.dir + "/demo.lcm";
    out.gt = out.dir + "/gt.tum";
    out.rig = out.dir + "/rig.yaml";
    const std::string sim = kBin + "/livo-sim --scenario " + std::string(LIVO_SOURCE_DIR) +
                            "/config/sim/demo.yaml --out " + out.log + " --gt " + out.gt + " --rig " + out.rig +
                            " > " + out.dir + "/sim.txt 2>&1";
    if (std::system(sim.c_str()) != 0) {
      out.error = "livo-sim failed: " + readFile(out.dir + "/sim.txt");
      return out;
    }
    const std::string run = kBin + "/livo-run " + out.log + " --config " + out.rig + " --out " + out.dir +
                            "/single --quiet > " + out.dir + "/run.txt 2>&1";
    if (std::system(run.c_str()) != 0) {
      out.error = "livo-run failed: " + readFile(out.dir + "/run.txt");
      return out;
    }
    out.single = readTum(out.dir + "/single/trajectory.tum");
    out.ok = true;
    return out;
  }();
  return d;
}

double ate(const Trajectory& gt, const Trajectory& est) { return evaluate(gt, est, EvalConfig{}).ate.translation_m.rmse; }

/// The four processes in `ns`, writing into `out` (logs there too).
struct Suite {
  std::unique_ptr<Child> mapserver, estimator, preprocess, exporter;
  const Netns& ns;
  std::string rig, out;
  Suite(const Netns& n, const std::string& rig_path, const std::string& out_dir, bool with_mapserver = true)
      : ns(n), rig(rig_path), out(out_dir) {
    std::filesystem::create_directories(out);
    if (with_mapserver) startMapServer("mapserver.txt");
    estimator = std::make_unique<Child>(ns.exec({kBin + "/livo-estimator", "--config", rig, "--lcm-url", kUrl,
                                                 "--idle-exit", "6"}),
                                        out + "/estimator.txt");
    preprocess = std::make_unique<Child>(ns.exec({kBin + "/livo-preprocess", "--config", rig, "--lcm-url", kUrl,
                                                  "--idle-exit", "3"}),
                                         out + "/preprocess.txt");
    exporter = std::make_unique<Child>(ns.exec({kBin + "/livo-exporter", "--config", rig, "--lcm-url", kUrl, "--out",
                                                out + "/export", "--idle-exit", "10"}),
                                       out + "/exporter.txt");
    for (const char* log : {"/estimator.txt", "/preprocess.txt", "/exporter.txt"}) awaitReady(out + log);
  }
  /// Each process prints its channels "... on URL" once it has subscribed.
  static void awaitReady(const std::string& log) {
    EXPECT_TRUE(waitUntil([&] { return readFile(log).find(" on " + kUrl) != std::string::npos; }, 60))
        << log << ":\n" << readFile(log);
  }
  void startMapServer(const std::string& log_name) {
    mapserver = std::make_unique<Child>(ns.exec({kBin + "/livo-mapserver", "--config", rig, "--lcm-url", kUrl,
                                                 "--map-file", out + "/map.bin"}),
                                        out + "/" + log_name);
    awaitReady(out + "/" + log_name);
  }
  /// Waits until the exporter has written `n` poses (trajectory.tum is flushed per line).
  bool awaitPoses(std::size_t n) const {
    return waitUntil([&] { return test::countLines(out + "/export/trajectory.tum") >= n + 1; }, 120);  // + header
  }
  /// Waits until the estimator's log says `text`.
  bool awaitEstimatorSays(const std::string& text) const {
    return waitUntil([&] { return readFile(out + "/estimator.txt").find(text) != std::string::npos; }, 120);
  }
  std::unique_ptr<Child> play(const std::string& log) const {
    return std::make_unique<Child>(ns.exec({"lcm-logplayer", "--lcm-url=" + kUrl, "--speed=1", log}),
                                   out + "/player.txt");
  }
  /// Waits for the chain to drain (idle exits), then stops the map server.
  void finish() {
    EXPECT_EQ(preprocess->wait(120), 0) << readFile(out + "/preprocess.txt");
    EXPECT_EQ(estimator->wait(120), 0) << readFile(out + "/estimator.txt");
    if (exporter) {
      EXPECT_EQ(exporter->wait(120), 0) << readFile(out + "/exporter.txt");
    }
    mapserver->signal(SIGINT);
    EXPECT_EQ(mapserver->wait(60), 0);
  }
};

}  // namespace

TEST(SuiteNetns, FourProcessesMatchLivoRunAndGroundTruth) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!test::haveTool("lcm-logplayer")) LIVO_SKIP() << "lcm-logplayer missing";
  const DemoLog& d = demoLog();
  ASSERT_TRUE(d.ok) << d.error;
  // A map server that answers late on a loaded machine must not change the result: the estimator
  // waits up to 10 s for each answer here (250 ms by default), so the two runs see the same frames and
  // answers whatever the load.
  const std::string rig = d.dir + "/rig_patient.yaml";
  std::ofstream(rig) << readFile(d.rig) << "\nestimator:\n  map_timeout_ms: 10000\n  fast_timeout_ms: 10000\n";
  Suite suite(ns, rig, d.dir + "/suite");
  auto player = suite.play(d.log);
  EXPECT_EQ(player->wait(120), 0) << readFile(suite.out + "/player.txt");
  suite.finish();

  const std::string est_log = readFile(suite.out + "/estimator.txt");
  const std::string map_log = readFile(suite.out + "/mapserver.txt");
  std::cout << "estimator:\n" << est_log << "map server:\n" << map_log;
  const Trajectory split = readTum(suite.out + "/export/trajectory.tum");
  ASSERT_GT(split.size(), d.single.size() * 9 / 10) << est_log;
  const Trajectory gt = readTum(d.gt);
  const double ate_single = ate(gt, d.single), ate_split = ate(gt, split);
  std::cout << "demo: livo-run ATE " << ate_single * 100 << " cm (" << d.single.size() << " poses), four processes "
            << ate_split * 100 << " cm (" << split.size() << " poses)\n";
  // No timeouts: lock step, the same frames and answers as livo-run. The trajectories still part by
  // floating-point order (first at 4.2 s by 11 um: the frames cross LCM as floats, and a patch sample
  // rounded to a whole gray level can flip, which the photometric update then follows). Measured
  // 2026-12-05: livo-run 0.518 cm, four processes 0.626 cm (1.08 mm apart); earlier the same day, with
  // another selector, 0.49165 / 0.49161 cm. Bounds about twice the larger figures.
  EXPECT_NE(est_log.find(", timeouts 0,"), std::string::npos) << est_log;
  EXPECT_LE(std::abs(ate_split - ate_single), 0.0022) << "the suite and livo-run agree";
  EXPECT_LE(ate_split, 0.0125);
  EXPECT_NE(map_log.find("saved " + suite.out + "/map.bin"), std::string::npos) << map_log;
  EXPECT_NE(readFile(suite.out + "/export/stats.json").find("\"frames\""), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(suite.out + "/export/map.pcd"));
}

TEST(SuiteNetns, FourProcessesPlusLivoLoopReproduceLivoRunLoop) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!test::haveTool("lcm-logplayer")) LIVO_SKIP() << "lcm-logplayer missing";
  // The revisit scenario cut to one lap and the start of the second (56 s; test_pipeline_loop's log).
  const std::string dir = test::tempDir("suite_loop");
  const std::string log = dir + "/revisit.lcm", gt = dir + "/gt.tum", rig = dir + "/rig.yaml";
  ASSERT_EQ(std::system((kBin + "/livo-sim --scenario " + std::string(LIVO_SOURCE_DIR) + "/config/sim/revisit.yaml --out " +
                         log + " --gt " + gt + " --rig " + rig + " --duration 56 --quiet > " + dir + "/sim.txt 2>&1")
                            .c_str()),
            0)
      << readFile(dir + "/sim.txt");
  const std::string patient = dir + "/rig_patient.yaml";
  std::ofstream(patient) << readFile(rig) << "\nestimator:\n  map_timeout_ms: 10000\n  fast_timeout_ms: 10000\n";
  ASSERT_EQ(std::system((kBin + "/livo-run " + log + " --config " + patient + " --out " + dir +
                         "/single --loop --no-maps --quiet > " + dir + "/run.txt 2>&1")
                            .c_str()),
            0)
      << readFile(dir + "/run.txt");

  // livo-loop starts with the sinks and exits (idle) before the exporter, whose idle time then restarts
  // with livo-loop's final correction.
  Child loop(ns.exec({kBin + "/livo-loop", "--config", patient, "--lcm-url", kUrl, "--idle-exit", "8"}), dir + "/loop.txt");
  Suite::awaitReady(dir + "/loop.txt");
  Suite suite(ns, patient, dir + "/suite");
  auto player = suite.play(log);
  EXPECT_EQ(player->wait(180), 0) << readFile(suite.out + "/player.txt");
  EXPECT_EQ(loop.wait(180), 0) << readFile(dir + "/loop.txt");
  suite.finish();

  const std::string loop_log = readFile(dir + "/loop.txt");
  std::cout << "livo-loop:\n" << loop_log;
  const Trajectory single = readTum(dir + "/single/trajectory_map.tum");
  const Trajectory split = readTum(suite.out + "/export/trajectory_map.tum");
  const Trajectory split_odom = readTum(suite.out + "/export/trajectory.tum");
  const Trajectory truth = readTum(gt);
  EXPECT_EQ(split.size(), split_odom.size());
  ASSERT_GT(split.size(), single.size() * 9 / 10);
  const double ate_single = ate(truth, single), ate_split = ate(truth, split), ate_odom = ate(truth, split_odom);
  std::cout << "revisit 56 s: livo-run --loop map frame ATE " << ate_single * 100 << " cm; four processes + livo-loop "
            << ate_split * 100 << " cm (odometry " << ate_odom * 100 << " cm)\n";
  EXPECT_NE(loop_log.find("loops accepted"), std::string::npos) << loop_log;
  EXPECT_NE(readFile(suite.out + "/export/stats.json").find("\"map_frame_final\": 1"), std::string::npos)
      << "the exporter got livo-loop's final correction";
  // 2026-12-06: livo-run --loop 1.171 cm, four processes + livo-loop 1.124 cm (odometry 1.547 cm), 161
  // keyframes and 5 loops in both; livo-loop's peak RSS 26 MB. The two part by floating-point order
  // (the scan crosses LCM as floats). Bounds about twice the figures.
  EXPECT_LE(std::abs(ate_split - ate_single), 0.002) << "the suite with livo-loop and livo-run --loop agree";
  EXPECT_LE(ate_split, 0.023);
}

// A second run localising in a site map between processes: livo-loop --prior-map gives the map frame,
// livo-mapserver --prior-map serves the map's planes once it has; against livo-run --prior-map on the
// same log. The map: one lap of the revisit block (livo-run --save-map); the second run: 30 s in the same
// world from 150 m further along the path with other noise.
TEST(SuiteNetns, FourProcessesPlusLivoLoopLocaliseInASiteMap) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!test::haveTool("lcm-logplayer")) LIVO_SKIP() << "lcm-logplayer missing";
  const std::string dir = test::tempDir("suite_reloc");
  std::string second = readFile(std::string(LIVO_SOURCE_DIR) + "/config/sim/revisit.yaml");
  second.replace(second.find("seed: 11\n"), 9, "seed: 12\n");
  second.replace(second.find("world:\n"), 7, "world:\n  seed: 11\n");
  second.replace(second.find("trajectory:\n"), 12, "trajectory:\n  start_m: 150.0\n");
  std::ofstream(dir + "/second.yaml") << second;
  const auto sim = [&](const std::string& scenario, const std::string& name, double s) {
    return std::system((kBin + "/livo-sim --scenario " + scenario + " --out " + dir + "/" + name + ".lcm --gt " + dir +
                        "/" + name + "_gt.tum --rig " + dir + "/" + name + "_rig.yaml --duration " + std::to_string(s) +
                        " --quiet > " + dir + "/sim.txt 2>&1")
                           .c_str());
  };
  ASSERT_EQ(sim(std::string(LIVO_SOURCE_DIR) + "/config/sim/revisit.yaml", "first", 48.0), 0) << readFile(dir + "/sim.txt");
  ASSERT_EQ(sim(dir + "/second.yaml", "second", 30.0), 0) << readFile(dir + "/sim.txt");
  const std::string site = dir + "/site";
  ASSERT_EQ(std::system((kBin + "/livo-run " + dir + "/first.lcm --config " + dir + "/first_rig.yaml --out " + dir +
                         "/run1 --save-map " + site + " --no-maps --quiet > " + dir + "/run1.txt 2>&1")
                            .c_str()),
            0)
      << readFile(dir + "/run1.txt");
  const std::string rig = dir + "/rig_patient.yaml";
  std::ofstream(rig) << readFile(dir + "/second_rig.yaml") << "\nestimator:\n  map_timeout_ms: 10000\n  fast_timeout_ms: 10000\n";
  ASSERT_EQ(std::system((kBin + "/livo-run " + dir + "/second.lcm --config " + rig + " --out " + dir +
                         "/single --prior-map " + site + " --no-maps --quiet > " + dir + "/run2.txt 2>&1")
                            .c_str()),
            0)
      << readFile(dir + "/run2.txt");

  Child loop(ns.exec({kBin + "/livo-loop", "--config", rig, "--lcm-url", kUrl, "--idle-exit", "8", "--prior-map", site}),
             dir + "/loop.txt");
  Suite::awaitReady(dir + "/loop.txt");
  Suite suite(ns, rig, dir + "/suite", /*with_mapserver=*/false);
  suite.mapserver = std::make_unique<Child>(ns.exec({kBin + "/livo-mapserver", "--config", rig, "--lcm-url", kUrl,
                                                     "--prior-map", site}),
                                            suite.out + "/mapserver.txt");
  Suite::awaitReady(suite.out + "/mapserver.txt");
  auto player = suite.play(dir + "/second.lcm");
  EXPECT_EQ(player->wait(120), 0) << readFile(suite.out + "/player.txt");
  EXPECT_EQ(loop.wait(120), 0) << readFile(dir + "/loop.txt");
  suite.finish();

  const std::string map_log = readFile(suite.out + "/mapserver.txt");
  std::cout << "livo-loop:\n" << readFile(dir + "/loop.txt") << "map server:\n" << map_log;
  EXPECT_NE(map_log.find("localised in the site map: serving its planes"), std::string::npos) << map_log;
  // Both without aligning the second run: the first run's map-frame alignment onto its ground truth.
  EvalConfig fixed;
  fixed.fixed_alignment = evaluate(readTum(dir + "/first_gt.tum"), readTum(dir + "/run1/trajectory_map.tum"), EvalConfig{}).T_gt_est;
  const Trajectory truth = readTum(dir + "/second_gt.tum");
  const Trajectory single = readTum(dir + "/single/trajectory_map.tum");
  const Trajectory split = readTum(suite.out + "/export/trajectory_map.tum");
  ASSERT_GT(split.size(), single.size() * 9 / 10);
  const EvalResult es = evaluate(truth, single, fixed), ep = evaluate(truth, split, fixed);
  std::cout << "second run in the site map: livo-run --prior-map mean " << es.ate.translation_m.mean * 100 << " cm, max "
            << es.ate.translation_m.max * 100 << " cm (" << single.size() << " poses); four processes + livo-loop "
            << ep.ate.translation_m.mean * 100 << " cm, max " << ep.ate.translation_m.max * 100 << " cm (" << split.size()
            << " poses)\n";
  // 2026-12-07: livo-run --prior-map mean 1.110 cm, max 3.84 cm; four processes + livo-loop 1.103 cm,
  // max 3.85 cm (286 poses each). Bounds about twice the figures
  // (the difference: a few millimetres of floating-point order, as for loop closure).
  EXPECT_LE(ep.ate.translation_m.mean, 0.025);
  EXPECT_LE(std::abs(ep.ate.translation_m.mean - es.ate.translation_m.mean), 0.002);
}

TEST(SuiteNetns, MapServerKilledAndRestartedEstimatorRecovers) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!test::haveTool("lcm-logplayer")) LIVO_SKIP() << "lcm-logplayer missing";
  const DemoLog& d = demoLog();
  ASSERT_TRUE(d.ok) << d.error;
  Suite suite(ns, d.rig, d.dir + "/restart");
  auto player = suite.play(d.log);
  // The demo gives 191 poses: kill the map server at about a third of them, restart it once the
  // estimator has run without answers.
  ASSERT_TRUE(suite.awaitPoses(65)) << readFile(suite.out + "/estimator.txt");
  suite.mapserver->signal(SIGKILL);
  suite.mapserver->wait(10);
  ASSERT_TRUE(suite.awaitEstimatorSays("no submap for request")) << readFile(suite.out + "/estimator.txt");
  suite.startMapServer("mapserver2.txt");
  EXPECT_EQ(player->wait(120), 0) << readFile(suite.out + "/player.txt");
  suite.finish();

  const std::string est_log = readFile(suite.out + "/estimator.txt");
  std::cout << "estimator:\n" << est_log;
  EXPECT_NE(est_log.find("no submap for request"), std::string::npos) << est_log;
  EXPECT_NE(est_log.find("the map server answers again"), std::string::npos) << est_log;
  const Trajectory split = readTum(suite.out + "/export/trajectory.tum");
  ASSERT_GT(split.size(), d.single.size() * 9 / 10) << "odometry kept coming while the map server was down\n" << est_log;
  const double e = ate(readTum(d.gt), split);
  std::cout << "demo with the map server killed for ~1 s: ATE " << e * 100 << " cm (" << split.size() << " poses)\n";
  // Measured 0.64 cm (2026-12-02; 1.08-1.18 cm before the start of 2026-12-01; the kill's timing
  // varies); about twice the worst seen.
  EXPECT_LE(e, 0.014) << "the estimator recovers on the rebuilt map";
}

TEST(SuiteNetns, EstimatorStartedBeforeTheMapServerAndExporterKilled) {
  Netns ns;
  if (!ns.ok) LIVO_SKIP() << ns.why;
  if (!test::haveTool("lcm-logplayer")) LIVO_SKIP() << "lcm-logplayer missing";
  const DemoLog& d = demoLog();
  ASSERT_TRUE(d.ok) << d.error;
  Suite suite(ns, d.rig, d.dir + "/late", /*with_mapserver=*/false);
  auto player = suite.play(d.log);
  // The estimator runs on its own (odometry without answers) for about 2 s of poses, then with the map
  // server until about 9 s of poses are exported.
  ASSERT_TRUE(suite.awaitEstimatorSays("no submap for request")) << readFile(suite.out + "/estimator.txt");
  ASSERT_TRUE(suite.awaitPoses(20)) << readFile(suite.out + "/estimator.txt");
  suite.startMapServer("mapserver.txt");
  ASSERT_TRUE(suite.awaitEstimatorSays("the map server answers again")) << readFile(suite.out + "/estimator.txt");
  ASSERT_TRUE(suite.awaitPoses(85)) << readFile(suite.out + "/estimator.txt");
  suite.exporter->signal(SIGKILL);  // no chance to flush anything at exit
  suite.exporter->wait(10);
  const std::size_t lines_at_kill = test::countLines(suite.out + "/export/trajectory.tum");
  suite.exporter.reset();
  EXPECT_EQ(player->wait(120), 0);
  suite.finish();

  const std::string est_log = readFile(suite.out + "/estimator.txt");
  EXPECT_NE(est_log.find("no submap for request"), std::string::npos) << est_log;
  EXPECT_NE(est_log.find("the map server answers again"), std::string::npos) << est_log;
  // The killed exporter's trajectory: every line written so far is complete and readable.
  Trajectory kept;
  ASSERT_NO_THROW(kept = readTum(suite.out + "/export/trajectory.tum"));
  std::cout << "exporter killed after " << kept.size() << " poses (" << lines_at_kill << " lines at the kill)\n";
  EXPECT_GE(kept.size() + 1, lines_at_kill - 1) << "at most the pose being written is lost";
  EXPECT_GT(kept.size(), 50u) << "about 9 s of 10 Hz poses were exported before the kill";
  const double e = ate(readTum(d.gt), kept);
  std::cout << "estimator alone for 3 s, then with the map server: ATE " << e * 100 << " cm over " << kept.size()
            << " poses\n";
  // Measured 2.19 cm (2026-12-07, the one start; 0.52 cm on 2026-12-02 when the start's own throwaway map
  // confirmed the rest and held v = 0 tightly): without the map server the filter starts with the
  // velocity unknown (sigma 2 m/s) and nothing observes it for about 2 s, so the first updates on the
  // map server's new map come with a prior metres wide. About twice the measured figure.
  EXPECT_LE(e, 0.044) << "without the map server first, then LiDAR-inertial on the new map";
}

TEST(SuiteBinaries, HelpAndErrorsNameTheProblem) {
  const std::string dir = test::tempDir("suite_cli");
  auto run = [&](const std::string& cmd) {
    const int rc = std::system((cmd + " > " + dir + "/out.txt 2>&1").c_str());
    return std::make_pair(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, readFile(dir + "/out.txt"));
  };
  const std::string cfg = std::string(LIVO_SOURCE_DIR) + "/config/avia.yaml";
  auto [rc, out] = run(kBin + "/livo-estimator --help");
  EXPECT_EQ(rc, 0);
  EXPECT_NE(out.find("--visual-mode"), std::string::npos) << out;
  std::tie(rc, out) = run(kBin + "/livo-mapserver --help");
  EXPECT_EQ(rc, 0);
  EXPECT_NE(out.find("--memory-cap-mb"), std::string::npos) << out;
  std::tie(rc, out) = run(kBin + "/livo-mapserver --config " + cfg + " --lcm-url memq:// --map-mode bogus");
  EXPECT_EQ(rc, 2);
  EXPECT_NE(out.find("'bogus'"), std::string::npos) << out;
  std::tie(rc, out) = run(kBin + "/livo-estimator --config " + cfg + " --lcm-url memq:// --visual-mode sometimes");
  EXPECT_EQ(rc, 2);
  EXPECT_NE(out.find("'sometimes'"), std::string::npos) << out;
  std::ofstream(dir + "/junk.map") << "junk";
  std::tie(rc, out) = run(kBin + "/livo-mapserver --config " + cfg + " --lcm-url memq:// --map-file " + dir + "/junk.map");
  EXPECT_EQ(rc, 1);
  EXPECT_NE(out.find("map file " + dir + "/junk.map: not a livo map file"), std::string::npos) << out;
  std::string text = readFile(cfg);
  const std::string key = "map_timeout_ms: 250.0";
  ASSERT_NE(text.find(key), std::string::npos);
  text.replace(text.find(key), key.size(), "map_timeout_ms: -1");
  std::ofstream(dir + "/bad.yaml") << text;
  std::tie(rc, out) = run(kBin + "/livo-estimator --config " + dir + "/bad.yaml --lcm-url memq://");
  EXPECT_EQ(rc, 2);
  EXPECT_NE(out.find("estimator.map_timeout_ms"), std::string::npos) << out;
}
