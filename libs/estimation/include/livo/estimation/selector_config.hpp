// Settings of the LiDAR-degeneration-aware adaptive visual frame selector (rig section `selector`,
// plus the top-level `environment` that picks the keyframe threshold defaults).
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/modes.hpp"

#include <string>

namespace livo {

struct SelectorConfig {
  Environment environment = Environment::Indoor;
  double degeneracy_threshold = 0.15;  ///< sigma_min = sqrt(lambda_min / N) below this: degenerate
  int degenerate_frames = 3;           ///< consecutive degenerate frames before the state is declared
  double tau_translation_m = 1.0;      ///< tau_predef translation (defaults: indoor 1 m, outdoor 2 m)
  double tau_rotation_deg = 60.0;      ///< tau_predef rotation
  /// Information trigger (not in the paper; docs/algorithms.md section 9): an image is also a keyframe
  /// when the last visual update's information on the rotation or the position is, along some axis, at
  /// least this multiple of the filter's own after the LiDAR update: the image would make that sigma
  /// sqrt(1 + ratio) times smaller (8: three times). 0: off (motion thresholds only).
  double information_ratio = 8.0;

  /// Reads `environment` and the `selector` section.
  void load(const ConfigNode& root);
};

}  // namespace livo
