// LiDAR-degeneration-aware adaptive visual frame selector (docs/algorithms.md "The two ideas", 2):
//   degenerate LiDAR -> every image runs the visual update;
//   otherwise only keyframes: the pose moved more than tau = sqrt(3) * sigma_min * tau_predef since
//   the last visual update, in translation or rotation (sqrt(3) sigma_min is 1 for a perfectly
//   conditioned scene, so tau shrinks towards 0 as the LiDAR constraint weakens);
//   or (an addition, `selector.information_ratio`, default 8) the image knows the pose much better
//   than the filter does: per 3x3 marginal of the rotation and of the position, the information the
//   last visual update brought, I = P_after^-1 - P_before^-1 (the position's carried into the body frame
//   so that it turns with the camera), against the marginal covariance P after this frame's LiDAR
//   update: the largest generalised eigenvalue of (I, P^-1), i.e. the factor 1 + lambda by which the
//   image would cut the variance along the best axis, at or above the ratio.
//   The trigger follows the configured IMU and LiDAR noise through P, with no threshold in metres or
//   degrees. Measured (2026-12-02, config/sim/stress/aggressive_*.yaml, seeds 5-7): lambda has a median
//   of 2-3 with the shipped rigs' IMU, where the LiDAR posterior is close to what an image adds and the
//   motion thresholds decide, and of 20-33 with a 10x noisier IMU, where nearly every image is used.
#pragma once

#include "livo/common/modes.hpp"
#include "livo/estimation/selector_config.hpp"
#include "livo/estimation/state.hpp"

#include <string>

namespace livo {

// VisualMode: livo/common/modes.hpp.

class FrameSelector {
 public:
  /// The marginal information of the rotation and of the position (in body-frame position errors).
  struct PoseInfo {
    Mat3 rotation = Mat3::Zero();
    Mat3 position_body = Mat3::Zero();
  };

  FrameSelector(SelectorConfig cfg, VisualMode mode) : cfg_(std::move(cfg)), mode_(mode) {}

  /// Whether the image of this frame runs the visual update; P: the covariance after the LiDAR update.
  bool select(const NavState& x, const StateCov& P, double sigma_min, bool degenerate) const;
  /// Records a frame whose visual update ran: its pose and the covariance before and after the update.
  void markUsed(const NavState& x, const StateCov& P_before, const StateCov& P_after);

  /// Step 4 of the pipeline (frame_pipeline.hpp): feeds one frame's sigma_min (frames with matches only) and returns
  /// whether the LiDAR is degenerate: sigma_min below degeneracy_threshold for degenerate_frames
  /// frames in a row.
  bool degenerate(bool have_matches, double sigma_min) {
    if (!have_matches) return false;
    const bool low = sigma_min < cfg_.degeneracy_threshold;
    low_sigma_run_ = low ? low_sigma_run_ + 1 : 0;
    high_sigma_run_ = low ? 0 : high_sigma_run_ + 1;
    if (high_sigma_run_ >= cfg_.degenerate_frames) constrained_once_ = true;
    return low_sigma_run_ >= cfg_.degenerate_frames;
  }
  /// Until the LiDAR has constrained every direction (sigma_min at or above the threshold) for
  /// degenerate_frames frames in a row once, adaptive mode runs the visual update on every image: the
  /// first frames after a start build the map and the first visual points, and a start whose LiDAR
  /// registrations slide along a weak direction (a street's axis at speed) would otherwise bake a
  /// wrong velocity into both (random rig 28: a car at 8.8 m/s, 3.8 m ATE over 30 s; 13 cm when the
  /// first frames use the camera). A start in a well-conditioned scene costs degenerate_frames images.
  bool constrainedOnce() const { return constrained_once_; }

  /// Keyframe thresholds for a given sigma_min (translation m, rotation rad).
  double translationThreshold(double sigma_min) const;
  double rotationThreshold(double sigma_min) const;
  /// The information trigger's lambda for state x with covariance P: the larger of the rotation's and
  /// the position's (0 before any visual update; a block whose P is not positive definite gives 0).
  double informationRatio(const NavState& x, const StateCov& P) const;

 private:
  SelectorConfig cfg_;
  VisualMode mode_;
  bool have_last_ = false;
  int low_sigma_run_ = 0;   ///< consecutive frames with sigma_min below the threshold
  int high_sigma_run_ = 0;  ///< consecutive frames with sigma_min at or above it
  bool constrained_once_ = false;
  NavState last_;
  PoseInfo last_info_;  ///< the last visual update's information
};

/// The information a measurement update added to the rotation's and the position's marginals,
/// P_after^-1 - P_before^-1 per 3x3 block (symmetric, positive semi-definite, zero where a block is not
/// positive definite), the position's carried into the body frame of `x`: R^T I R.
FrameSelector::PoseInfo poseInformationGain(const NavState& x, const StateCov& P_before, const StateCov& P_after);

}  // namespace livo
