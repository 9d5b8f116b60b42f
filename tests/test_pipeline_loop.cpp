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

}  // namespace
