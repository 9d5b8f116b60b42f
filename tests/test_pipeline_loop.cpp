// livo-run --loop as users run it: the simulator's revisit scenario cut to one lap and the start of the
// second, the map-frame trajectory (trajectory_map.tum) against the ground truth and the odometry's, the
// loop counters in stats.json, a bad loop key refused with its name.
// livo-test-bins: livo-sim livo-run livo-eval
// livo-test-whole
#include "pipeline_cli_test_util.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using livo::test::bin;
using livo::test::run;
using livo::test::slurp;

namespace {

std::size_t lines(const fs::path& p) {
  std::ifstream in(p);
  std::size_t n = 0;
  for (std::string l; std::getline(in, l);) n += !l.empty() && l[0] != '#';
  return n;
}

double ate(const std::string& gt, const fs::path& est, const fs::path& dir) {
  const livo::test::Ran ev = livo::test::runSplit(bin("livo-eval") + " --json --gt " + gt + " --est " + est.string(), dir);
  EXPECT_EQ(ev.rc, 0) << ev.err;
  const std::size_t at = ev.out.find("\"ate_rmse_m\":");
  if (at == std::string::npos) return 1e9;
  return std::stod(ev.out.substr(at + 13));
}

TEST(LivoRunLoop, ClosesTheLoopOfTheRevisitScenario) {
  for (const char* b : {"livo-sim", "livo-run", "livo-eval"})
    if (!fs::exists(bin(b))) LIVO_SKIP() << bin(b) << " not built";
  const fs::path dir = fs::temp_directory_path() / ("livo_test_loop_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string log = (dir / "revisit.lcm").string(), gt = (dir / "gt.tum").string(), rig = (dir / "rig.yaml").string();
  // 56 s: 4 s of start, one 41 s lap of the 340 m block, 11 s (90 m) of the second.
  ASSERT_EQ(run(bin("livo-sim") + " --scenario " + LIVO_SOURCE_DIR + "/config/sim/revisit.yaml --out " + log + " --gt " +
                gt + " --rig " + rig + " --duration 56 --quiet"),
            0);
  const fs::path out = dir / "loop", plain = dir / "plain";
  const livo::test::Ran r = livo::test::runSplit(
      bin("livo-run") + " " + log + " --config " + rig + " --out " + out.string() + " --loop --no-maps --threads 1 --quiet", dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("loop closure: "), std::string::npos) << r.out;
  ASSERT_TRUE(fs::exists(out / "trajectory_map.tum"));
  EXPECT_EQ(lines(out / "trajectory_map.tum"), lines(out / "trajectory.tum"));
  const std::string stats = slurp(out / "stats.json");
  const double accepted = livo::test::jsonNumberAfter(stats, "\"counters\"", "loop_accepted");
  const double keyframes = livo::test::jsonNumberAfter(stats, "\"counters\"", "loop_keyframes");
  for (const char* k : {"loop_rejected_too_few_points", "loop_rejected_no_convergence", "loop_rejected_low_overlap",
                        "loop_rejected_high_residual", "loop_rejected_inconsistent", "loop_points_held"})
    EXPECT_NO_THROW(livo::test::jsonNumberAfter(stats, "\"counters\"", k)) << k;
  const double odom = ate(gt, out / "trajectory.tum", dir), map = ate(gt, out / "trajectory_map.tum", dir);
  std::printf("[ revisit 56 s ] %.0f keyframes, %.0f loops; ATE odometry %.2f cm, map frame %.2f cm\n", keyframes,
              accepted, 100 * odom, 100 * map);
  EXPECT_GE(keyframes, 150);
  EXPECT_GE(accepted, 2);
  // The map frame is pulled onto the first lap where the second one starts. 2026-12-06: 161 keyframes,
  // 5 loops, ATE 1.50 cm (odometry) -> 1.17 cm (map frame).
  EXPECT_LE(map, odom);
  EXPECT_LT(map, 0.025);

  // Without --loop: no trajectory_map.tum; the same odometry.
  ASSERT_EQ(run(bin("livo-run") + " " + log + " --config " + rig + " --out " + plain.string() +
                " --no-maps --threads 1 --quiet --max-frames 50"),
            0);
  EXPECT_FALSE(fs::exists(plain / "trajectory_map.tum"));

  // A bad key of the loop section: exit 2 naming it (read and checked also without --loop).
  {
    std::ofstream bad(dir / "bad.yaml");
    bad << slurp(rig) << "loop:\n  loop_sigma_m: -1\n";
  }
  const livo::test::Ran b = livo::test::runSplit(
      bin("livo-run") + " " + log + " --config " + (dir / "bad.yaml").string() + " --out " + (dir / "bad").string(), dir);
  EXPECT_EQ(b.rc, 2);
  EXPECT_NE(b.err.find("loop.loop_sigma_m: must be > 0"), std::string::npos) << b.err;
  fs::remove_all(dir);
}

// Two runs in one world (issue "Come back to a place", item 4): the revisit block mapped by a first run
// (livo-run --save-map), a second run from another start with other noise localising in that map with no
// initial pose (livo-run --prior-map); its map-frame trajectory against the truth with the first run's
// alignment only (livo-eval --align-like: the map's frame, not the second run, is aligned).
TEST(LivoRunLoop, ASecondRunLocalisesInTheSavedMapOfTheFirst) {
  for (const char* b : {"livo-sim", "livo-run", "livo-eval"})
    if (!fs::exists(bin(b))) LIVO_SKIP() << bin(b) << " not built";
  const fs::path dir = fs::temp_directory_path() / ("livo_test_reloc_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string scenario = slurp(std::string(LIVO_SOURCE_DIR) + "/config/sim/revisit.yaml");
  std::string second = scenario;
  ASSERT_NE(second.find("seed: 11\n"), std::string::npos);
  second.replace(second.find("seed: 11\n"), 9, "seed: 12\n");
  second.replace(second.find("world:\n"), 7, "world:\n  seed: 11\n");
  second.replace(second.find("trajectory:\n"), 12, "trajectory:\n  start_m: 150.0\n");
  {
    std::ofstream(dir / "first.yaml") << scenario;
    std::ofstream(dir / "second.yaml") << second;
  }
  const auto sim = [&](const std::string& name, double duration_s) {
    return run(bin("livo-sim") + " --scenario " + (dir / (name + ".yaml")).string() + " --out " +
               (dir / (name + ".lcm")).string() + " --gt " + (dir / (name + "_gt.tum")).string() + " --rig " +
               (dir / (name + "_rig.yaml")).string() + " --duration " + std::to_string(duration_s) + " --quiet");
  };
  // The first run: one lap (48 s); the second: 30 s from 150 m along the block, the other way round the
  // first's start.
  ASSERT_EQ(sim("first", 48.0), 0);
  ASSERT_EQ(sim("second", 30.0), 0);
  const std::string site = (dir / "site").string();
  const livo::test::Ran r1 = livo::test::runSplit(bin("livo-run") + " " + (dir / "first.lcm").string() + " --config " +
                                                      (dir / "first_rig.yaml").string() + " --out " +
                                                      (dir / "run1").string() + " --save-map " + site +
                                                      " --no-maps --threads 1 --quiet",
                                                  dir);
  ASSERT_EQ(r1.rc, 0) << r1.err;
  EXPECT_NE(r1.out.find("site map: "), std::string::npos) << r1.out;
  const livo::test::Ran r2 = livo::test::runSplit(bin("livo-run") + " " + (dir / "second.lcm").string() + " --config " +
                                                      (dir / "second_rig.yaml").string() + " --out " +
                                                      (dir / "run2").string() + " --prior-map " + site +
                                                      " --no-maps --threads 1",
                                                  dir);
  ASSERT_EQ(r2.rc, 0) << r2.err;
  EXPECT_NE(r2.err.find("localised in the site map at t="), std::string::npos) << r2.err;
  const std::string stats = slurp(dir / "run2" / "stats.json");
  const double to_localise = livo::test::jsonNumberAfter(stats, "\"counters\"", "reloc_time_from_first_frame_s");
  EXPECT_GT(livo::test::jsonNumberAfter(stats, "\"counters\"", "reloc_prior_keyframes_inserted"), 20)
      << "the map's keyframes near the robot serve the LiDAR update";
  const livo::test::Ran ev = livo::test::runSplit(
      bin("livo-eval") + " --json --gt " + (dir / "second_gt.tum").string() + " --est " +
          (dir / "run2" / "trajectory_map.tum").string() + " --align-like " + (dir / "run1" / "trajectory_map.tum").string() +
          " --align-like-gt " + (dir / "first_gt.tum").string(),
      dir);
  ASSERT_EQ(ev.rc, 0) << ev.err;
  EXPECT_NE(ev.out.find("\"alignment_fixed\": true"), std::string::npos) << ev.out;
  const double mean = livo::test::jsonNumberAfter(ev.out, "{", "ate_mean_m");
  const double max = livo::test::jsonNumberAfter(ev.out, "{", "ate_max_m");
  std::printf("[ second run ] localised %.2f s after the log's first frame; map-frame error without aligning it: mean %.2f cm, "
              "max %.2f cm\n",
              to_localise, 100 * mean, 100 * max);
  // 2026-12-06: localised 1.50 s after the log's first frame (1.0 s of initialisation at rest, then two
  // agreeing tries 0.5 s apart); mean 1.11 cm, max 3.8 cm (the map's keyframes serve the LiDAR update
  // from the localised frame on; before the seeder looked only after 1 m of travel: 1.26 / 7.4 cm). The target:
  // within 3 s, mean <= 10 cm. Bounds about twice.
  EXPECT_GE(to_localise, 0.0);
  EXPECT_LE(to_localise, 3.0);
  EXPECT_LE(mean, 0.026);
  EXPECT_LE(max, 0.08);  // 3.8 cm 2026-12-06, 3.70 cm 2026-12-08

  // --prior-map with --loop: refused (exit 2) naming both.
  const livo::test::Ran both = livo::test::runSplit(bin("livo-run") + " " + (dir / "second.lcm").string() + " --config " +
                                                        (dir / "second_rig.yaml").string() + " --out " +
                                                        (dir / "both").string() + " --prior-map " + site + " --loop",
                                                    dir);
  EXPECT_EQ(both.rc, 2);
  EXPECT_NE(both.err.find("--prior-map with --loop"), std::string::npos) << both.err;
  // A site map that is not there: exit 1 naming it.
  const livo::test::Ran bad = livo::test::runSplit(bin("livo-run") + " " + (dir / "second.lcm").string() + " --config " +
                                                       (dir / "second_rig.yaml").string() + " --out " +
                                                       (dir / "bad").string() + " --prior-map " + (dir / "nomap").string(),
                                                   dir);
  EXPECT_EQ(bad.rc, 1);
  EXPECT_NE(bad.err.find("nomap/site.bin: cannot open"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

}  // namespace
