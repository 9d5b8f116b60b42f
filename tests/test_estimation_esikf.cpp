// libs/estimation Esikf, the one owner of the filter state: its propagation is ImuPropagator's on its
// own state (bit for bit), propagateBefore uses exactly the samples strictly inside (state time, cut),
// the camera time offset's prior replaces t_d's row and column, and start() says whether that prior
// is in P already (a resumed run) or comes at the next visual frame.
#include "livo/estimation/esikf.hpp"
#include "livo/estimation/imu.hpp"

#include "estimation_test_util.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace livo;
using livo_test::randomState;

namespace {

std::vector<ImuSample> samplesFrom(Utime t0, int n, std::mt19937& rng) {
  std::normal_distribution<double> nd(0, 1);
  std::vector<ImuSample> out(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    out[std::size_t(i)].utime = t0 + 5000 * i;
    out[std::size_t(i)].gyro = 0.3 * Vec3(nd(rng), nd(rng), nd(rng));
    out[std::size_t(i)].accel = Vec3(0, 0, 9.81) + Vec3(nd(rng), nd(rng), nd(rng));
  }
  return out;
}

StateCov randomCov(std::mt19937& rng) {
  std::normal_distribution<double> nd(0, 1);
  StateCov A;
  for (int i = 0; i < A.rows(); ++i)
    for (int j = 0; j < A.cols(); ++j) A(i, j) = 0.01 * nd(rng);
  return A * A.transpose() + StateCov::Identity() * 1e-4;
}

}  // namespace

TEST(Esikf, PropagationIsTheImuPropagatorsOnTheOneState) {
  std::mt19937 rng(11);
  ImuConfig imu;
  const NavState x0 = randomState(rng);
  const StateCov P0 = randomCov(rng);
  const std::vector<ImuSample> samples = samplesFrom(x0.utime, 21, rng);
  const Utime t_end = x0.utime + 100000;
  Esikf f(imu);
  EXPECT_FALSE(f.started());
  f.start(x0, P0, 9.81);
  ASSERT_TRUE(f.started());
  EXPECT_DOUBLE_EQ(f.accelScale(), 9.81);
  std::vector<ImuTracePoint> trace;
  f.propagate(samples, t_end, &trace);
  NavState x = x0;
  StateCov P = P0;
  std::vector<ImuTracePoint> expected_trace;
  ImuPropagator(imu, 9.81).propagate(x, P, samples, t_end, &expected_trace);
  EXPECT_EQ(f.x().utime, t_end);
  EXPECT_EQ((f.x().p_world_imu - x.p_world_imu).norm(), 0.0);
  EXPECT_EQ((f.x().R_world_imu - x.R_world_imu).norm(), 0.0);
  EXPECT_EQ((f.P() - P).norm(), 0.0);
  EXPECT_EQ(trace.size(), expected_trace.size());
  const FilterState snap = f.snapshot();
  EXPECT_EQ((snap.P - P).norm(), 0.0);
  EXPECT_DOUBLE_EQ(snap.accel_scale, 9.81);
}

TEST(Esikf, PropagateBeforeUsesOnlyTheSamplesInsideTheInterval) {
  std::mt19937 rng(12);
  ImuConfig imu;
  const NavState x0 = randomState(rng);
  const StateCov P0 = randomCov(rng);
  // Samples from 50 ms before the state to 150 ms after it; the cut at 100 ms.
  const std::vector<ImuSample> all = samplesFrom(x0.utime - 50000, 41, rng);
  const Utime cut = x0.utime + 100000;
  Esikf f(imu);
  f.start(x0, P0, 1.0);
  f.propagateBefore(all, cut);
  std::vector<ImuSample> inside;
  for (const auto& s : all)
    if (s.utime > x0.utime && s.utime < cut) inside.push_back(s);
  ASSERT_EQ(inside.size(), 19u);  // 5 ms apart, both ends excluded
  NavState x = x0;
  StateCov P = P0;
  ImuPropagator(imu, 1.0).propagate(x, P, inside, cut, nullptr);
  EXPECT_EQ(f.x().utime, cut);
  EXPECT_EQ((f.x().v_world - x.v_world).norm(), 0.0);
  EXPECT_EQ((f.P() - P).norm(), 0.0);
  // Nothing inside: the state stays where it is.
  Esikf g(imu);
  g.start(x0, P0, 1.0);
  g.propagateBefore(all, x0.utime + 1);
  EXPECT_EQ(g.x().utime, x0.utime);
  EXPECT_EQ((g.P() - P0).norm(), 0.0);
}

TEST(Esikf, TimeOffsetPriorReplacesItsRowAndColumn) {
  std::mt19937 rng(13);
  Esikf f{ImuConfig{}};
  NavState x0 = randomState(rng);
  x0.time_offset_s = 0.02;
  const StateCov P0 = randomCov(rng);
  f.start(x0, P0, 1.0);
  EXPECT_FALSE(f.timeOffsetPriorSet()) << "a new start: the prior comes at the next visual frame";
  f.setTimeOffsetPrior(0.005);
  EXPECT_TRUE(f.timeOffsetPriorSet());
  constexpr int td = sidx::kTimeOffset;
  EXPECT_EQ(f.x().time_offset_s, 0.0);
  EXPECT_DOUBLE_EQ(f.P()(td, td), 0.005 * 0.005);
  for (int i = 0; i < P0.rows(); ++i) {
    if (i == td) continue;
    EXPECT_EQ(f.P()(td, i), 0.0);
    EXPECT_EQ(f.P()(i, td), 0.0);
    for (int j = 0; j < P0.cols(); ++j)
      if (j != td) {
        ASSERT_EQ(f.P()(i, j), P0(i, j)) << i << "," << j;
      }
  }
  // Another estimator's state carries its prior: a resumed start keeps it.
  f.start(x0, P0, 1.0, /*time_offset_prior_in_P=*/true);
  EXPECT_TRUE(f.timeOffsetPriorSet());
  EXPECT_EQ(f.x().time_offset_s, 0.02);
  f.start(x0, P0, 1.0);
  EXPECT_FALSE(f.timeOffsetPriorSet());
}
