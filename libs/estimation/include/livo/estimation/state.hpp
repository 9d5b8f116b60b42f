// The filter state of the error-state iterated Kalman filter (docs/algorithms.md section 1).
//
// Error state (20-D, in this order): dtheta [0:3] (rotation, right perturbation R Exp(dtheta)),
// dp [3:6], dtau [6] (inverse exposure time relative to the first image, tau_0 = 1), dv [7:10],
// dbg [10:13], dba [13:16], dg [16:19], dt_d [19] (the camera's time offset beyond camera.time_offset_s,
// estimated with camera.estimate_time_offset; otherwise no update touches it). Everything but rotation
// is additive.
#pragma once

#include "livo/common/so3.hpp"
#include "livo/common/types.hpp"

#include <Eigen/Core>

namespace livo {

constexpr int kStateDim = 20;
namespace sidx {
constexpr int kRot = 0, kPos = 3, kExposure = 6, kVel = 7, kBg = 10, kBa = 13, kGrav = 16, kTimeOffset = 19;
}
using StateVec = Eigen::Matrix<double, kStateDim, 1>;
using StateCov = Eigen::Matrix<double, kStateDim, kStateDim>;

/// Nominal state: IMU (body) pose in the world frame, velocity, biases, gravity, inverse exposure.
struct NavState {
  Utime utime = 0;
  Mat3 R_world_imu = Mat3::Identity();
  Vec3 p_world_imu = Vec3::Zero();
  double inv_exposure = 1.0;  ///< tau
  Vec3 v_world = Vec3::Zero();
  Vec3 bg = Vec3::Zero();  ///< gyro bias, rad/s
  Vec3 ba = Vec3::Zero();  ///< accelerometer bias, m/s^2
  Vec3 g_world = Vec3(0, 0, -9.81);
  /// t_d, s: an image stamped (after camera.time_offset_s) at t was captured at t + t_d.
  double time_offset_s = 0.0;

  /// x [+] delta.
  NavState boxplus(const StateVec& delta) const;
  /// this [-] other, such that other.boxplus(this->boxminus(other)) == *this.
  StateVec boxminus(const NavState& other) const;
  Pose pose() const;
};

/// Initial covariance (docs/algorithms.md section 1): 0.01 I, with 1e-5 for tau, biases and gravity; t_d
/// (1 ms)^2 as a placeholder that keeps P invertible: no Jacobian has a t_d column unless the offset is
/// estimated, and then the pipeline sets its prior (camera.time_offset_sigma_s).
StateCov initialCovariance();

}  // namespace livo
