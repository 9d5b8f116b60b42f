// The error-state iterated Kalman filter's state: the one owner of the navigation state, its
// covariance, the accelerometer units and the camera time offset's prior. The phases of a frame act
// on it in turn (frame_pipeline.hpp lists them): IMU propagation (propagate), the LiDAR update
// (lidarUpdate in lio_update.hpp, through x() / P()), the photometric update (runVisualStep in
// visual_step.hpp, the same way). docs/algorithms.md sections 1, 2 and 4.
#pragma once

#include "livo/estimation/imu.hpp"
#include "livo/estimation/state.hpp"

#include <memory>
#include <vector>

namespace livo {

/// The whole filter state after a frame: what a restarted estimator needs to continue in the same world
/// frame (Esikf::snapshot / FramePipeline::resume).
struct FilterState {
  NavState state;
  StateCov P = StateCov::Zero();
  double accel_scale = 1.0;  ///< accelerometer units found at initialisation (ImuPropagator)
};

class Esikf {
 public:
  explicit Esikf(const ImuConfig& imu) : imu_(imu) {}

  /// Sets the state, its covariance and the accelerometer units (an initialiser's result, or another
  /// estimator's last state). The camera time offset's prior is set at the next visual frame, unless
  /// `time_offset_prior_in_P` (another estimator's state carries it already).
  void start(const NavState& x, const StateCov& P, double accel_scale, bool time_offset_prior_in_P = false);
  bool started() const { return propagator_ != nullptr; }

  /// Propagates to `t_end` through `samples` (ImuPropagator::propagate); `trace` may be null.
  void propagate(const std::vector<ImuSample>& samples, Utime t_end, std::vector<ImuTracePoint>* trace);
  /// Propagates through the samples of `samples` after the state's time and before `cut`, up to `cut`
  /// (the samples of an initialisation window's tail or of an outage, before a frame's own).
  void propagateBefore(const std::vector<ImuSample>& samples, Utime cut);

  /// The state and covariance the updates act on.
  NavState& x() { return x_; }
  StateCov& P() { return P_; }
  const NavState& x() const { return x_; }
  const StateCov& P() const { return P_; }
  double accelScale() const { return propagator_ ? propagator_->accelScale() : 1.0; }
  FilterState snapshot() const { return FilterState{x_, P_, accelScale()}; }

  /// The camera time offset t_d: its prior (0 with variance sigma^2, no correlation) is set at the
  /// first visual frame after a start, and again whenever the estimate leaves 3 prior sigmas.
  bool timeOffsetPriorSet() const { return time_offset_prior_set_; }
  void setTimeOffsetPrior(double sigma_s);

 private:
  ImuConfig imu_;
  std::unique_ptr<ImuPropagator> propagator_;
  NavState x_;
  StateCov P_ = initialCovariance();
  bool time_offset_prior_set_ = false;
};

}  // namespace livo
