// IMU static initialisation, forward propagation with covariance, and the per-sample trace used to
// undistort LiDAR points (docs/algorithms.md section 1).
#pragma once

#include "livo/common/config.hpp"
#include "livo/estimation/state.hpp"

#include <string>
#include <vector>

namespace livo {

struct ImuConfig {
  double gyro_noise = 1.7e-3;       ///< rad/s/sqrt(Hz), continuous white-noise density
  double accel_noise = 2.0e-2;      ///< m/s^2/sqrt(Hz)
  double gyro_bias_walk = 1.9e-4;   ///< rad/s^2/sqrt(Hz)
  double accel_bias_walk = 3.0e-3;  ///< m/s^3/sqrt(Hz)
  double noise_scale = 1.0;         ///< multiplies the four densities (inflate for unmodelled effects)
  double inv_exposure_walk = 0.1;   ///< 1/sqrt(s), random walk of tau
  double gravity_m_s2 = 9.81;       ///< local gravity magnitude
  double rate_hz = 200.0;           ///< imu.rate_hz: nominal sample rate (the start's window span)
  bool gravity_align = true;        ///< rotate the world so that gravity is (0, 0, -g) (world z up)
  // The start (imu_init.hpp, lio_odometry.hpp):
  /// The filter starts once the IMU samples span init_samples samples at rate_hz: gravity from their
  /// mean specific force, whatever the rig does (no static test).
  int init_samples = 30;
  /// Prior sigma of the start's velocity (the start assumes none: v = 0). Set it to what the rig may be
  /// doing when it starts (a car that starts on the move: its speed).
  double init_speed_sigma_mps = 2.0;
  double init_gyro_bias_sigma_rad_s = 0.02;   ///< prior sigma of the gyro bias at the start
  double init_accel_bias_sigma_mps2 = 0.02;   ///< prior sigma of the accelerometer bias (never observed at start)

  /// Reads the `imu` section (noise densities, initialisation); errors name the key. The rate,
  /// imu.rate_hz, is read and checked by the preprocessing's config (PreprocessConfig, loaded first by
  /// PipelineConfig) and given as `rate_hz`.
  void load(const ConfigNode& imu, double rate_hz);
  /// Keys of the removed start rules (static test, motion initialiser, deadline) found in the section:
  /// read and ignored (load() keeps them out of the unknown-key error), named in the start's message.
  std::vector<std::string> ignored_keys;
};

/// State at one IMU sample, with the unbiased rate and world acceleration used for the interval that
/// starts there; used for backward undistortion.
struct ImuTracePoint {
  Utime utime = 0;
  Mat3 R_world_imu = Mat3::Identity();
  Vec3 p_world_imu = Vec3::Zero();
  Vec3 v_world = Vec3::Zero();
  Vec3 acc_world = Vec3::Zero();  ///< R a_hat + g over the interval
  Vec3 omega = Vec3::Zero();      ///< unbiased angular rate over the interval, body frame
};

/// Forward propagation of state and covariance through IMU samples (mid-point integration).
class ImuPropagator {
 public:
  ImuPropagator(const ImuConfig& cfg, double accel_scale) : cfg_(cfg), accel_scale_(accel_scale) {}

  /// Propagates `x` (at x.utime) and `P` to `t_end` using the samples (time ordered, covering
  /// [x.utime, t_end] as far as available; the last sample is held beyond its time). Appends one trace
  /// point per interval to `trace` (cleared first) and a final one at t_end.
  void propagate(NavState& x, StateCov& P, const std::vector<ImuSample>& samples, Utime t_end,
                 std::vector<ImuTracePoint>* trace) const;

  /// Pose at time t from a trace (t within or slightly outside it: extrapolates with the end intervals).
  static Pose poseAt(const std::vector<ImuTracePoint>& trace, Utime t);

  /// The error-state transition F of one interval of length dt starting at `x` with the raw samples
  /// `gyro` / `accel` (identity except the blocks of docs/algorithms.md section 1; what propagate() uses
  /// in P' = F P F^T + Q).
  StateCov transition(const NavState& x, const Vec3& gyro, const Vec3& accel, double dt) const;

  /// The factor the raw accelerometer samples are multiplied by (1: m/s^2; g when they are in g).
  double accelScale() const { return accel_scale_; }

 private:
  void step(NavState& x, StateCov& P, const Vec3& gyro, const Vec3& accel, double dt, ImuTracePoint* tp) const;
  ImuConfig cfg_;
  double accel_scale_;
};

}  // namespace livo
