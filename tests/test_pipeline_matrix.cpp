// The random rig matrix's CI subset (issue "Any rig, any start"; scripts/bench --matrix runs the full
// one): nine rigs drawn by livo::sim::drawRandomScenario (the distribution of config/sim/README.md,
// section "Random rigs") with fixed seeds, 12 s each, adaptive + hybrid in one process against the
// simulator's ground truth, each held to the matrix's pass criteria: first pose at most 3 s after the
// first data, no gap between poses over 0.5 s after it, ATE at most max(5 cm, 0.5 % of the path), no
// NaN. The seeds are chosen so that every hard class of the generator has a rig:
// each rig names its classes below, and the test checks that the draw still holds them.
// livo-test-long: 900
// livo-test-deps: livo_sim livo_estimation livo_eval
#include "livo/sim/random_scenario.hpp"
#include "pipeline_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

using namespace livo;

namespace {

constexpr double kSeconds = 12.0;

/// A rig of the subset: its seed and the classes it stands for. Classes are the generator's
/// (RandomScenario::classes) plus two checked here on the scenario: "car" (trajectory.motion car) and
/// "corridor-at-rest" (a corridor, at rest for at least 1.5 s).
struct Rig {
  int seed;
  std::vector<std::string> classes;
};

std::ostream& operator<<(std::ostream& o, const Rig& r) { return o << "seed " << r.seed; }

class RandomRig : public ::testing::TestWithParam<Rig> {};

}  // namespace

TEST_P(RandomRig, StartsEarlyHoldsAndStaysAccurate) {
  const Rig& rig = GetParam();
  const auto drawn = sim::drawRandomScenario(static_cast<std::uint64_t>(rig.seed), kSeconds);
  std::cout << "random rig " << rig.seed << ": " << drawn.summary << "\n";
  sim::SimScenario sc = sim::parseScenario(drawn.yaml);
  sc.source = "random rig " + std::to_string(rig.seed);
  // The rig still stands for its classes (a change of the distribution moves the seeds).
  for (const std::string& c : rig.classes) {
    if (c == "car") EXPECT_EQ(sc.trajectory.motion, "car") << "class " << c;
    else if (c == "corridor-at-rest") EXPECT_TRUE(sc.world.kind == "corridor" && sc.trajectory.static_s >= 1.5) << "class " << c;
    else EXPECT_NE(std::find(drawn.classes.begin(), drawn.classes.end(), c), drawn.classes.end()) << "class " << c;
  }
  const livo_test::RunSummary r = livo_test::runScenario(sc, 0.0, "adaptive");
  ASSERT_FALSE(r.est.empty()) << "no pose at all";
  EXPECT_LE(r.first_pose_s, 3.0) << "first pose within 3 s of the first data";
  EXPECT_LE(r.max_pose_gap_s, 0.5) << "no gap over 0.5 s after the first pose";
  for (const auto& p : r.est) ASSERT_TRUE(p.T_world_body.matrix().allFinite()) << "NaN pose at " << p.t;
  const double path = r.eval.path_length_m;
  const double bound = std::max(0.05, 0.005 * path);
  EXPECT_LE(r.eval.ate.translation_m.rmse, bound) << "ATE over " << path << " m of path";
  // No false alarm of the health checks (docs/algorithms.md section 12): no frame lost; the degraded
  // share is printed (measured 2026-12-07 on the nine rigs: 0 lost and 0 degraded of 1447 frames).
  const auto lost = std::count(r.health.begin(), r.health.end(), HealthState::Lost);
  const auto degraded = std::count(r.health.begin(), r.health.end(), HealthState::Degraded);
  std::cout << "health: " << lost << " lost, " << degraded << " degraded of " << r.health.size() << " frames\n";
  EXPECT_EQ(lost, 0) << "lost frames on a rig that tracks";
}

// One rig per class, chosen from the summaries `livo-sim --random SEED` prints (seeds 1-300); where a
// rig holds a second class it is named too. Cost: a street (the car), the rest rooms, a wall and a
// corridor with small cameras: about 369 s of CPU (5:12 wall on the 2-core machine, 2026-12-07) against
// 699 s for the nine rigs of the previous subset (seeds 1-7, 28, 33 of the previous distribution).
// Not in the subset because today's start fails it: a CAR moving from the first sample on a street.
// Seeds 5, 70 and 76 (spinning32 at 5 Hz with a 15 Hz camera, Mid-360 at 5 Hz with a 15 Hz camera,
// spinning32 at 10 Hz) give 16.6, 8.8 and 16.9 m ATE over 12 s with the one start (2026-12-07 ef6c130;
// 16.8 m, 42.8 m and 4.8 cm with the start's rules before). The filter starts at v = 0 while the car does
// 5-6 m/s: the second scan is 0.5-1.2 m from where the prior puts it, beyond the association's reach, and
// the map of one sparse scan holds too few planes for a registration to find it (268 of 4000 points
// matched at best, tried 2026-12-07), so each scan is inserted where the filter believes and the map
// moves with the car. The moving-start class is held here by a drone in a room (seed 47).
INSTANTIATE_TEST_SUITE_P(
    Matrix, RandomRig,
    ::testing::Values(
        // A start in motion, no rest: a drone at 1.1 m/s from the first sample (room, spinning32, 400 Hz
        // IMU at 5x the noise).
        Rig{47, {"moving-start", "spinning-room"}},
        // A fast start: a drone in a room at rest 0.35 s, then 2.9 m/s^2 (Avia at 5 Hz, 100 Hz IMU).
        Rig{42, {"fast-start"}},
        // A fast start of a car: at rest 0.2 s, then 2 m/s^2 up to 9.9 m/s (street, sparse Mid-360, camera
        // at 3x the LiDAR).
        Rig{107, {"fast-start", "car", "fast-camera"}},
        // Vibration aliased by the IMU's rate: 2 m/s^2 and 0.052 rad/s at 186 Hz on a 100 Hz IMU (seen at
        // 14.4 Hz), handheld in a room at rest 2.6 s.
        Rig{202, {"vibration-aliased"}},
        // A spinning LiDAR on a wall (spinning32, 83k pts/s; camera at 2x the LiDAR), at rest 2.8 s.
        Rig{231, {"spinning-wall", "fast-camera"}},
        // A spinning LiDAR in a room (spinning32, 83k pts/s), at rest 1.8 s.
        Rig{237, {"spinning-room"}},
        // A camera at 2x the LiDAR: 20 Hz with a 10 Hz Mid-360 in a room, at rest 2.2 s, 100 Hz IMU.
        Rig{248, {"fast-camera"}},
        // High IMU noise: 14.3x the shipped densities, handheld in a room (Mid-360), at rest 1.9 s.
        Rig{71, {"noisy-imu"}},
        // At rest in a corridor (2.6 s; Mid-360, 320 x 256 camera): the LiDAR-degenerate baseline.
        Rig{52, {"corridor-at-rest"}}),
    [](const ::testing::TestParamInfo<Rig>& info) { return "seed" + std::to_string(info.param.seed); });
