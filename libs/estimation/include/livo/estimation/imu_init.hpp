// Static IMU initialisation that follows the sensor's configured noise (docs/algorithms.md section 1).
//
// Every full window of init_samples samples is tested: it is static when the RMS deviation of its
// gyro samples is below ImuConfig::staticGyroThreshold() and that of its accelerometer samples (in
// m/s^2) below staticAccelThreshold(); both derive from the configured noise densities and rate (a
// documented factor, plus the rig's vibration margin), and its mean rate must be a plausible bias (at
// most 5 init_gyro_bias_sigma_rad_s: a steady turn is calm too). Of the static windows seen, the calmest (the
// smallest ratio of RMS deviation to threshold) is used, once the calm ends (a window in motion
// follows) or init_static_wait_s after the first sample, whichever comes first. A window in motion is
// never used: when none is static by then, noStaticWindow() says so and the odometry initialises
// from motion (lio_odometry.hpp); later static windows are still taken if they come first. An IMU
// cannot tell rest from constant velocity: the odometry confirms a chosen window with the LiDAR
// (motion_init.hpp) and reject()s it when the rig moved. By ImuConfig::deadlineSeconds() after the first
// sample the odometry starts whatever it has (lio_odometry.cpp): a chosen window the LiDAR could not
// confirm, else coarseState() (the window, its wait and the rate can never keep the first pose out).
//
// The state is at the end of the chosen window: gyro bias = mean gyro, gravity from the mean
// specific force (its norm also gives the accelerometer scale: g-unit IMUs), zero velocity. The
// covariance says what was observed: the gyro bias to sigma_gyro / sqrt(n) per axis, roll and pitch
// to sqrt(sigma_accel^2 / n + sigma_ba^2) / g (at rest a horizontal accelerometer bias looks like a
// tilt); yaw and position are the world frame's definition; the accelerometer bias itself is not
// observable at rest (its prior sigma_ba = init_accel_bias_sigma_mps2).
#pragma once

#include "livo/estimation/imu.hpp"
#include "livo/estimation/state.hpp"

#include <deque>
#include <string>
#include <vector>

namespace livo {

class ImuInitializer {
 public:
  explicit ImuInitializer(const ImuConfig& cfg) : cfg_(cfg) {}
  /// Adds a sample (time order; older or duplicate stamps are ignored). Returns done().
  bool add(const ImuSample& s);
  /// A static window was chosen: initialState() and friends are valid.
  bool done() const { return done_; }
  /// No static window within the wait: initialise from motion (static windows are still looked for).
  bool noStaticWindow() const { return no_static_; }
  /// Scale applied to every accelerometer reading: g / |mean accel| (about 9.81 for g-unit IMUs).
  double accelScale() const { return accel_scale_; }
  /// State at the end of the chosen window.
  NavState initialState() const { return state_; }
  /// Prior covariance from what the window observed (see the file comment).
  StateCov initialCovariance() const;
  /// The chosen window was not rest after all (the LiDAR saw the rig move: constant velocity looks
  /// like rest to an IMU): forget it; noStaticWindow() from now on, later windows are still tested.
  void reject();
  /// Start time of the chosen window.
  Utime windowStart() const { return best_.start; }
  /// Samples after the chosen window (the odometry propagates the state through them).
  std::vector<ImuSample> samplesAfterWindow() const;
  /// Time of the first sample (-1 before any).
  Utime firstSampleTime() const { return first_utime_; }
  std::string describe() const;
  /// While not done(): which condition is missing, with the numbers (the last full window's RMS
  /// deviations against the thresholds).
  std::string status() const;
  /// A coarse state for a start without a static window or a motion solution (the deadline,
  /// ImuConfig::deadlineSeconds()): gravity from the mean specific force of the last second of samples,
  /// zero velocity, the gyro bias from the mean rate when it is a plausible bias; `P` the prior of
  /// initialCovariance() with roll and pitch to `tilt_sigma_rad` (what that mean can be off by) and the
  /// gyro bias to its prior sigma (the caller sets the velocity's). False without samples or gravity.
  bool coarseState(NavState& x, StateCov& P, double& tilt_sigma_rad, double& accel_scale) const;

 private:
  struct WindowStats {
    Vec3 mean_gyro = Vec3::Zero(), mean_accel = Vec3::Zero();
    double rms_gyro = 0, rms_accel = 0, scale = 1.0;
    double score = 0;  ///< max(rms_gyro / gyro threshold, rms_accel / accel threshold); static below 1
    Utime start = 0, end = 0;
    int n = 0;
  };
  bool windowStats(WindowStats& w) const;  ///< the last init_samples samples; false without gravity
  void choose(const WindowStats& w);
  /// The start's prior: roll and pitch to var_tilt about the world's horizontal axes (R the start's
  /// attitude; yaw defines the world), gyro bias var_bg, accelerometer bias its prior.
  StateCov prior(const Mat3& R, double var_tilt, double var_bg) const;

  ImuConfig cfg_;
  std::deque<ImuSample> samples_;  ///< since the first sample, bounded (see add())
  Utime first_utime_ = -1;
  bool have_best_ = false, done_ = false, no_static_ = false;
  WindowStats best_;
  WindowStats last_;  ///< the last full window (status())
  double accel_scale_ = 1.0;
  NavState state_;
};

}  // namespace livo
