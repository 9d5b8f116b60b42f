// Ground-truth trajectory of the IMU (body) frame: analytic pose, velocity, acceleration and angular
// rate at any time, C2-smooth so that the simulated IMU is exact.
//
// Construction (path.cpp): a closed geometric path (loop / lissajous / waypoints) is sampled densely,
// given a speed profile that respects the speed, turn-rate and acceleration limits, and resampled at
// uniform time steps into the control points of a periodic uniform cubic B-spline P(tau) (C2).
// Evaluation: tau(t) stays at 0 during the static period, then a quintic-smoothstep ramp brings
// dtau/dt from 0 to c <= 1 (C2), then tau advances at rate c. Yaw follows the path tangent (or faces
// `look_at`), roll / pitch / yaw carry a sway and z a step bob (by default only a handheld rig's:
// TrajectoryConfig::motion), both faded in with the ramp.
// R_world_imu = Rz(yaw) Ry(pitch) Rx(roll), body x forward, y left, z up.
#pragma once

#include "livo/common/so3.hpp"
#include "livo/sim/scenario.hpp"

#include <vector>

namespace livo::sim {

/// Full kinematic state of the body at one time.
struct BodyState {
  Pose T_world_imu = Pose::Identity();
  Vec3 v_world = Vec3::Zero();      ///< m/s
  Vec3 a_world = Vec3::Zero();      ///< m/s^2 (kinematic, gravity not included)
  Vec3 omega_body = Vec3::Zero();   ///< rad/s, body frame
};

/// Closed path polyline (metres) for a trajectory config in a world (last point != first).
std::vector<Vec3> makePathPolyline(const TrajectoryConfig& cfg, const WorldConfig& world);

class SimTrajectory {
 public:
  SimTrajectory() = default;
  /// Builds from the scenario; throws ConfigError when the path cannot satisfy the limits.
  SimTrajectory(const TrajectoryConfig& cfg, const WorldConfig& world);

  /// State at `t` seconds after the start (t < 0 is treated as 0).
  BodyState state(double t) const;
  Pose pose(double t) const { return state(t).T_world_imu; }

  /// The geometric path (dense polyline) the spline follows: worlds keep it free of obstacles.
  const std::vector<Vec3>& path() const { return path_; }
  /// Seconds per lap at cruise, path length in metres.
  double lapTime() const { return knot_dt_ * static_cast<double>(ctrl_.size()) / time_scale_; }
  double pathLength() const { return path_length_; }
  /// Time at which the body starts moving.
  double staticDuration() const { return cfg_.static_s; }
  /// Peak speed and angular rate found by sampling one lap (after construction).
  double peakSpeed() const { return peak_speed_; }
  double peakRate() const { return peak_rate_; }

 private:
  struct SplineEval {
    Vec3 p, dp, ddp;  // derivatives with respect to tau
  };
  SplineEval spline(double tau) const;
  void timeWarp(double t, double& tau, double& dtau, double& ddtau) const;
  void sway(double t, Vec3& angles, Vec3& rates, double& z, double& dz, double& ddz) const;
  void measurePeaks();
  /// ctrl_ and knot_dt_ from the speed v at each path sample (seg[i]: length from sample i to i + 1).
  void placeControlPoints(const std::vector<double>& seg, const std::vector<double>& v);
  /// time_scale_ <= 1 so that the final spline keeps speed_mps and `max_rot` (rad/s); throws if it cannot.
  void fitTimeScale(double max_rot);

  TrajectoryConfig cfg_;
  std::vector<Vec3> path_;
  double path_length_ = 0.0;
  std::vector<Vec3> ctrl_;  ///< periodic B-spline control points
  double knot_dt_ = 0.2;    ///< tau between control points, s
  double time_scale_ = 1.0; ///< c: cruise dtau/dt
  bool look_at_ = false;
  Vec3 target_ = Vec3::Zero();
  double peak_speed_ = 0.0, peak_rate_ = 0.0;
};

}  // namespace livo::sim
