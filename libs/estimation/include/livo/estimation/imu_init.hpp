// The start's IMU part (docs/algorithms.md section 1): the first window of samples gives gravity's
// direction, the accelerometer's unit and a gyro bias guess, each with the uncertainty the window
// leaves; the filter starts from them at once and its LiDAR updates pull velocity, gravity and biases in.
//
// There is no static test: an IMU cannot tell rest from constant velocity, and a calm window at
// a car's speed, a vibrating rotorcraft's rest and a walk differ only in the values the filter
// estimates. Once the samples span one window (ImuConfig::init_samples at the configured rate):
// - gravity: the mean specific force of the samples of the last second. It is off by the mean
//   horizontal acceleration a_h over that second: a varying one shows in the samples' spread, a
//   steady one lengthens the mean to sqrt(g^2 + a_h^2). The tilt sigma is
//   atan2(max(RMS deviation, sqrt(| |mean|^2 - g^2 |)), g), clamped to [2, 15] degrees (a few tenths
//   of m/s^2 hide in the noise and an IMU's scale error; in g units the norm is the scale: only the
//   spread counts);
// - accelerometer scale: g / |mean| when |mean| < 4 (an IMU in g units), else 1;
// - gyro bias: the mean rate when it is a plausible bias (below 3 init_gyro_bias_sigma_rad_s), with
//   that prior sigma either way (a slow turn looks the same);
// - velocity 0 with sigma init_speed_sigma_mps; position the origin; accelerometer bias 0 with
//   init_accel_bias_sigma_mps2; yaw defines the world.
#pragma once

#include "livo/estimation/imu.hpp"
#include "livo/estimation/state.hpp"

#include <deque>
#include <string>

namespace livo {

class ImuInitializer {
 public:
  explicit ImuInitializer(const ImuConfig& cfg) : cfg_(cfg) {}
  /// Adds a sample (time order; older or duplicate stamps are ignored). Returns ready().
  bool add(const ImuSample& s);
  /// The samples span one window (init_samples at rate_hz): start() can be called.
  bool ready() const;
  /// Time of the first sample (-1 before any).
  Utime firstSampleTime() const { return first_utime_; }
  /// The start state at the last sample and its prior covariance (see the file comment);
  /// `tilt_sigma_rad` and `accel_scale` for the message and the propagator. False without samples or
  /// without a usable gravity (a mean specific force of zero or not finite).
  bool start(NavState& x, StateCov& P, double& tilt_sigma_rad, double& accel_scale) const;
  /// While the filter has not started: what is missing, with the numbers (the window, or a gravity).
  std::string status() const;

 private:
  ImuConfig cfg_;
  std::deque<ImuSample> samples_;  ///< the last second (at least one window)
  Utime first_utime_ = -1;
};

}  // namespace livo
