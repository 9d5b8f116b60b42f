// LiDAR-degeneration-aware adaptive visual frame selector (ALGORITHMS.md, top, idea 2):
//   degenerate LiDAR -> every image runs the visual update;
//   otherwise only keyframes: the pose moved more than tau = sqrt(3) * sigma_min * tau_predef since
//   the last visual update, in translation or rotation (sqrt(3) sigma_min is 1 for a perfectly
//   conditioned scene, so tau shrinks towards 0 as the LiDAR constraint weakens).
#pragma once

#include "livo/estimation/selector_config.hpp"
#include "livo/estimation/state.hpp"

#include <string>

namespace livo {

enum class VisualMode { Adaptive, All, Off };
VisualMode parseVisualMode(const std::string& s);  ///< throws std::invalid_argument

class FrameSelector {
 public:
  FrameSelector(SelectorConfig cfg, VisualMode mode) : cfg_(std::move(cfg)), mode_(mode) {}

  /// Whether the image of this frame runs the visual update.
  bool select(const NavState& x, double sigma_min, bool degenerate) const;
  /// Records the pose of a frame whose visual update ran.
  void markUsed(const NavState& x);

  /// Step 3 of the pipeline: feeds one frame's sigma_min (frames with matches only) and returns
  /// whether the LiDAR is degenerate: sigma_min below degeneracy_threshold for degenerate_frames
  /// frames in a row.
  bool degenerate(bool have_matches, double sigma_min) {
    if (!have_matches) return false;
    low_sigma_run_ = sigma_min < cfg_.degeneracy_threshold ? low_sigma_run_ + 1 : 0;
    return low_sigma_run_ >= cfg_.degenerate_frames;
  }

  /// Keyframe thresholds for a given sigma_min (translation m, rotation rad).
  double translationThreshold(double sigma_min) const;
  double rotationThreshold(double sigma_min) const;

 private:
  SelectorConfig cfg_;
  VisualMode mode_;
  bool have_last_ = false;
  int low_sigma_run_ = 0;  ///< consecutive frames with sigma_min below the threshold
  NavState last_;
};

}  // namespace livo
