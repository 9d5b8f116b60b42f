// Settings of the LiDAR-degeneration-aware adaptive visual frame selector (rig section `selector`,
// plus the top-level `environment` that picks the keyframe threshold defaults).
#pragma once

#include "livo/common/config.hpp"

#include <string>

namespace livo {

struct SelectorConfig {
  std::string environment = "indoor";  ///< indoor | outdoor
  double degeneracy_threshold = 0.07;  ///< sigma_min (L2-normalised eigenvalues) below this: degenerate
  int degenerate_frames = 3;           ///< consecutive degenerate frames before the state is declared
  double tau_translation_m = 1.0;      ///< tau_predef translation (defaults: indoor 1 m, outdoor 2 m)
  double tau_rotation_deg = 60.0;      ///< tau_predef rotation

  /// Reads `environment` and the `selector` section.
  void load(const ConfigNode& root);
};

}  // namespace livo
