// The filter's start end to end (filter_start.hpp, docs/algorithms.md section 1 "Start"): simulated rigs
// that the start must handle without a rule for any of them, LiDAR-inertial (camera off: the start
// does not use it), against the simulator's ground truth:
//  - a car at constant speed from the first sample (an IMU cannot tell it from rest), spinning LiDAR,
//    consumer-grade IMU;
//  - a rig at rest in a corridor (the LiDAR cannot see the axis: its fixes are no evidence of motion
//    either), noisy IMU, then walking;
//  - a drone in a room whose rotor vibration (2 m/s^2 at 91 Hz) is aliased by a 100 Hz IMU, a short
//    rest, then flying.
// Each: a pose from the first frame with enough IMU samples, the start observed within a second and a
// half, no pose more than 0.5 m off whose state says the start was observed, and the ATE bound.
// livo-test-long: 600
// livo-test-deps: livo_sim livo_estimation livo_eval
#include "pipeline_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace livo;

namespace {

std::string imuBlock(double rate, double grade, const std::string& extra = "") {
  std::ostringstream y;
  y << "imu:\n  rate_hz: " << rate << "\n  gyro_noise: " << 1.7e-4 * grade << "\n  accel_noise: " << 2.0e-3 * grade
    << "\n  gyro_bias_walk: " << 1.9e-5 * grade << "\n  accel_bias_walk: " << 3.0e-3 * grade
    << "\n  gyro_bias_init: [0.004, -0.003, 0.002]\n  accel_bias_init: [0.05, -0.04, 0.03]\n"
    << extra;
  return y.str();
}

const char* kCamera =
    "camera:\n  model: pinhole\n  width: 320\n  height: 256\n  fx: 200.0\n  fy: 200.0\n  cx: 159.5\n  cy: 127.5\n"
    "  rate_hz: 10.0\n";

/// The largest error of a pose whose start was observed, after the run's alignment.
double worstTrustedError(const livo_test::RunSummary& r) {
  double worst = 0.0;
  std::size_t g = 0;
  for (std::size_t i = 0; i < r.est.size(); ++i) {
    if (r.starting[i]) continue;
    while (g + 1 < r.gt.size() && r.gt[g + 1].t <= r.est[i].t) ++g;
    const Vec3 p = r.eval.T_gt_est.apply(Vec3(r.est[i].T_world_body.translation()));
    worst = std::max(worst, (p - r.gt[g].T_world_body.translation()).norm());
  }
  return worst;
}

struct Expect {
  double ate_m;         ///< bound on the ATE
  double observed_s;    ///< bound on the first observed pose, s after the first sample
};

void runAndCheck(const std::string& yaml, const char* name, const Expect& e) {
  sim::SimScenario sc = sim::parseScenario(yaml);
  sc.source = name;
  const livo_test::RunSummary r = livo_test::runScenario(sc, 0.0, "off");
  ASSERT_FALSE(r.est.empty()) << name << ": no pose";
  const double worst = worstTrustedError(r);
  std::cout << name << ": first pose " << r.first_pose_s << " s, start observed " << r.first_observed_s
            << " s, ATE " << r.eval.ate.translation_m.rmse * 100 << " cm over " << r.eval.path_length_m
            << " m, worst trusted pose " << worst * 100 << " cm\n";
  EXPECT_LE(r.first_pose_s, 0.5) << name << ": the filter starts at once";
  EXPECT_GE(r.first_observed_s, 0.0) << name << ": the start was never observed";
  EXPECT_LE(r.first_observed_s, e.observed_s) << name;
  EXPECT_LE(r.max_pose_gap_s, 0.5) << name;
  EXPECT_LE(worst, 0.5) << name << ": a pose said to be trusted is off";
  EXPECT_LE(r.eval.ate.translation_m.rmse, e.ate_m) << name << " over " << r.eval.path_length_m << " m";
}

}  // namespace

TEST(PipelineStart, ACarAtConstantSpeedFromTheFirstSample) {
  const std::string yaml = std::string(
                               "seed: 11\nduration_s: 8.0\n"
                               "world:\n  kind: street\n  size_m: [400.0, 250.0, 25.0]\n  clutter: 0.5\n"
                               "trajectory:\n  kind: loop\n  speed_mps: 10.0\n  max_rot_dps: 40.0\n  max_accel_mps2: 3.0\n"
                               "  corner_radius_m: 25.0\n  start_m: 100.0\n  static_s: 0.0\n  ramp_s: 0.0\n"
                               "lidar:\n  model: spinning32\n  rate_hz: 10.0\n  points_per_second: 160000\n"
                               "  range_noise_m: 0.02\n  max_range_m: 100.0\n  blind_m: 1.0\n") +
                           imuBlock(100.0, 12.0) + kCamera;
  runAndCheck(yaml, "car at 10 m/s from the first sample", {0.10, 1.5});
}

TEST(PipelineStart, AtRestInACorridorThenWalking) {
  const std::string yaml = std::string(
                               "seed: 12\nduration_s: 8.0\n"
                               "world:\n  kind: corridor\n  size_m: [200.0, 2.4, 2.8]\n"
                               "trajectory:\n  kind: loop\n  speed_mps: 1.0\n  max_rot_dps: 60.0\n  static_s: 3.0\n"
                               "  ramp_s: 1.0\n"
                               "lidar:\n  model: avia\n  rate_hz: 10.0\n  points_per_second: 120000\n"
                               "  range_noise_m: 0.02\n  max_range_m: 40.0\n  blind_m: 0.3\n") +
                           imuBlock(200.0, 12.0) + kCamera;
  runAndCheck(yaml, "at rest in a corridor", {0.10, 1.5});
}

TEST(PipelineStart, RotorVibrationAliasedByTheImuRate) {
  const std::string yaml = std::string(
                               "seed: 13\nduration_s: 8.0\n"
                               "world:\n  kind: room\n  size_m: [10.0, 8.0, 3.0]\n  clutter: 0.5\n"
                               "trajectory:\n  kind: loop\n  speed_mps: 1.5\n  max_rot_dps: 60.0\n  max_accel_mps2: 2.0\n"
                               "  static_s: 0.4\n  ramp_s: 1.0\n  sway_deg: 1.0\n  bob_m: 0.0\n"
                               "lidar:\n  model: mid360\n  rate_hz: 10.0\n  points_per_second: 100000\n"
                               "  range_noise_m: 0.02\n  max_range_m: 40.0\n  blind_m: 0.3\n") +
                           imuBlock(100.0, 3.0, "  vibration:\n    accel_mps2: 2.0\n    gyro_rad_s: 0.05\n    freq_hz: 91.0\n") +
                           kCamera;
  runAndCheck(yaml, "rotor vibration aliased at 100 Hz", {0.10, 1.5});
}
