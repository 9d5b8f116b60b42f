// Never silently lost (docs/algorithms.md section 12): faults of the simulator (config/sim/README.md:
// imu.fault_s, lidar.freeze_s) injected into the demo, end to end in one process against the ground
// truth. A diverging run must say `lost` within 0.5 s of its position error passing 0.5 m, a frozen
// LiDAR is recognised and left out, and the undisturbed demo has no frame out of `ok`.
// livo-test-whole (each scenario is simulated once)
// livo-test-deps: livo_sim livo_estimation livo_eval
#include "pipeline_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>

using namespace livo;
using livo_test::RunSummary;
using livo_test::runScenario;

namespace {

sim::SimScenario demo() { return sim::loadScenarioFile(livo_test::scenarioPath("demo")); }

/// Position error of every pose, the estimate aligned onto the ground truth with the poses before
/// `until_s` (seconds after the first sample: the undisturbed part), m.
std::vector<double> errorsAlignedBefore(const RunSummary& r, double until_s) {
  Trajectory before;
  for (const auto& p : r.est)
    if (p.t - r.t_start < until_s) before.push_back(p);
  const EvalResult e = evaluate(r.gt, before, EvalConfig{});
  std::vector<double> err;
  for (const auto& p : r.est) {
    const auto it = std::lower_bound(r.gt.begin(), r.gt.end(), p.t,
                                     [](const StampedPose& g, double t) { return g.t < t; });
    const StampedPose& g = it == r.gt.end() ? r.gt.back() : *it;
    err.push_back((e.T_gt_est.apply(p.T_world_body.translation()) - g.T_world_body.translation()).norm());
  }
  return err;
}

std::size_t count(const RunSummary& r, HealthState s) { return std::size_t(std::count(r.health.begin(), r.health.end(), s)); }

}  // namespace

TEST(PipelineHealth, TheUndisturbedDemoIsOkThroughout) {
  const RunSummary r = runScenario(demo(), 0.0);
  ASSERT_GT(r.est.size(), 150u);
  EXPECT_EQ(count(r, HealthState::Lost), 0u);
  EXPECT_EQ(count(r, HealthState::Degraded), 0u);  // measured 2026-12-07: 0 of 196
}

TEST(PipelineHealth, AnImuBiasJumpThatDivergesTheFilterIsLostWithinHalfASecond) {
  sim::SimScenario sc = demo();
  sc.imu.fault_s = {10.0, 11.0};
  sc.imu.fault_accel_mps2 = Vec3(6.0, 0.0, 0.0);  // 0.6 g along x for 1 s
  const RunSummary r = runScenario(sc, 0.0);
  const std::vector<double> err = errorsAlignedBefore(r, 10.0);
  std::size_t off = err.size(), lost = err.size();
  for (std::size_t i = 0; i < err.size(); ++i) {
    if (off == err.size() && err[i] > 0.5) off = i;
    if (lost == err.size() && r.health[i] == HealthState::Lost) lost = i;
  }
  ASSERT_LT(off, err.size()) << "the fault did not move the estimate 0.5 m: no test";
  ASSERT_LT(lost, err.size()) << "never said lost";
  const double delay = r.est[lost].t - r.est[off].t;
  std::printf("IMU fault: 0.5 m off at %.2f s, lost at %.2f s (delay %.2f s)\n", r.est[off].t - r.t_start,
              r.est[lost].t - r.t_start, delay);
  EXPECT_LE(delay, 0.5);  // measured 2026-12-07: lost at 10.40 s, 0.5 m off at 10.50 s (said before)
  // No frame more than 1 m off is written as ok.
  for (std::size_t i = 0; i < err.size(); ++i)
    EXPECT_FALSE(err[i] > 1.0 && r.health[i] == HealthState::Ok) << "t " << r.est[i].t - r.t_start << " err " << err[i];
  // Before the fault every frame is ok.
  for (std::size_t i = 0; i < err.size() && r.est[i].t - r.t_start < 10.0; ++i)
    EXPECT_EQ(r.health[i], HealthState::Ok) << r.est[i].t - r.t_start;
}

TEST(PipelineHealth, AFrozenLidarIsRecognisedAndTheFilterCarriesOnWithoutIt) {
  sim::SimScenario sc = demo();
  sc.lidar.freeze_s = {10.0, 12.0};  // the same sweep repeated for 2 s
  const RunSummary r = runScenario(sc, 0.0);
  const std::vector<double> err = errorsAlignedBefore(r, 10.0);
  double first_flag = -1, max_err = 0;
  std::size_t flagged = 0;
  for (std::size_t i = 0; i < r.est.size(); ++i) {
    const double t = r.est[i].t - r.t_start;
    if (t < 10.0) EXPECT_EQ(r.health[i], HealthState::Ok) << t;
    if (t >= 10.0 && first_flag < 0 && r.health[i] != HealthState::Ok) first_flag = t;
    flagged += t >= 10.0 && t < 12.0 && r.health[i] == HealthState::Degraded;
    max_err = std::max(max_err, err[i]);
  }
  std::printf("frozen LiDAR 10-12 s: first frame out of ok at %.2f s, %zu of the 20 frozen frames degraded, lost %zu, "
              "largest error %.3f m, ATE %.2f cm\n",
              first_flag, flagged, count(r, HealthState::Lost), max_err, r.eval.ate.translation_m.rmse * 100);
  // The repeated sweeps are recognised from the second on (the first is the last real one).
  EXPECT_GE(first_flag, 10.0);
  EXPECT_LE(first_flag, 10.15);  // measured 2026-12-07: 10.10 s, 19 of 20 frames degraded, none lost
  EXPECT_GE(flagged, 18u);
  EXPECT_EQ(count(r, HealthState::Lost), 0u);
  // The IMU carries the 2 s: no divergence (measured 2026-12-07: 3.4 cm at most).
  EXPECT_LT(max_err, 0.10);
}
