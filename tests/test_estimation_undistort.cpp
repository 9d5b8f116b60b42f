// Backward undistortion (libs/estimation undistort.hpp) against its brute-force definition: per point,
// the trace pose at the point's time by ImuPropagator::poseAt (a search and an expSO3 per point), then
// p_end = T_end^-1 T_t T_il p. The incremental walk must agree to float rounding for time-sorted points,
// points out of order, points before the trace, a zero angular rate and a single trace point.
#include "livo/estimation/undistort.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

using namespace livo;

namespace {

std::vector<ImuTracePoint> randomTrace(std::mt19937& rng, Utime t0, int n, double rate_scale) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<ImuTracePoint> trace;
  Utime t = t0;
  Mat3 R = Mat3::Identity();
  Vec3 p = Vec3::Zero(), v(1.5, -0.3, 0.1);
  for (int i = 0; i < n; ++i) {
    ImuTracePoint k;
    k.utime = t;
    k.R_world_imu = R;
    k.p_world_imu = p;
    k.v_world = v;
    k.acc_world = Vec3(g(rng), g(rng), g(rng));
    k.omega = rate_scale * Vec3(g(rng), g(rng), g(rng));
    trace.push_back(k);
    const double dt = 0.005;
    R = R * expSO3(k.omega * dt);
    p += v * dt + 0.5 * k.acc_world * dt * dt;
    v += k.acc_world * dt;
    t += fromSeconds(dt);
  }
  return trace;
}

LidarScan randomSweep(std::mt19937& rng, Utime t0, double span_s, int n, bool sorted) {
  std::uniform_real_distribution<double> u(0.0, span_s), d(-20.0, 20.0);
  LidarScan s;
  s.utime = t0;
  for (int i = 0; i < n; ++i) {
    LidarPoint p;
    p.p_lidar = Vec3(d(rng), d(rng), d(rng) * 0.2).cast<float>();
    p.time_offset_s = float(u(rng));
    p.intensity = float(i % 255);
    s.points.push_back(p);
  }
  if (sorted)
    std::sort(s.points.begin(), s.points.end(),
              [](const LidarPoint& a, const LidarPoint& b) { return a.time_offset_s < b.time_offset_s; });
  return s;
}

double maxDifference(const LidarScan& sweep, const std::vector<ImuTracePoint>& trace, const Pose& T_il) {
  const std::vector<LidarPoint> out = undistortToEnd(sweep, trace, T_il);
  EXPECT_EQ(out.size(), sweep.points.size());
  const Pose T_end_inv = ImuPropagator::poseAt(trace, trace.back().utime).inverse();
  double worst = 0.0;
  for (std::size_t i = 0; i < out.size() && i < sweep.points.size(); ++i) {
    const LidarPoint& p = sweep.points[i];
    const Utime t = sweep.utime + fromSeconds(p.time_offset_s);
    const Vec3 ref = T_end_inv * (ImuPropagator::poseAt(trace, t) * (T_il * p.p_lidar.cast<double>()));
    worst = std::max(worst, (out[i].p_lidar.cast<double>() - ref).norm());
    EXPECT_EQ(out[i].intensity, p.intensity);
    EXPECT_EQ(out[i].time_offset_s, p.time_offset_s);
  }
  return worst;
}

}  // namespace

TEST(Undistort, IncrementalWalkMatchesThePerPointDefinition) {
  std::mt19937 rng(14);
  Pose T_il = Pose::Identity();
  T_il.linear() = expSO3(Vec3(0.02, -0.4, 1.1));
  T_il.translation() = Vec3(0.04, 0.02, -0.05);
  const Utime t0 = 1'700'000'000'000'000;
  const auto trace = randomTrace(rng, t0, 21, 2.0);  // 0.1 s at 200 Hz, ~3.5 rad/s
  // Float output of points up to ~35 m away: rounding is ~2 um; the formulas agree far below that.
  EXPECT_LT(maxDifference(randomSweep(rng, t0, 0.1, 5000, true), trace, T_il), 1e-5) << "time-sorted";
  EXPECT_LT(maxDifference(randomSweep(rng, t0, 0.1, 5000, false), trace, T_il), 1e-5) << "out of order";
  // Points before the trace's start (a sweep that began before the previous frame) and after its end.
  EXPECT_LT(maxDifference(randomSweep(rng, t0 - 20'000, 0.14, 3000, true), trace, T_il), 1e-5) << "outside";
  const auto still = randomTrace(rng, t0, 21, 0.0);
  EXPECT_LT(maxDifference(randomSweep(rng, t0, 0.1, 2000, true), still, T_il), 1e-5) << "zero rate";
  const std::vector<ImuTracePoint> one(trace.begin(), trace.begin() + 1);
  EXPECT_LT(maxDifference(randomSweep(rng, t0, 0.1, 500, true), one, T_il), 1e-5) << "one trace point";
  EXPECT_TRUE(undistortToEnd(randomSweep(rng, t0, 0.1, 10, true), {}, T_il).empty());
}
