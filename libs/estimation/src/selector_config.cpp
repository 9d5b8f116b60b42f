#include "livo/estimation/selector_config.hpp"

#include <cmath>

namespace livo {

void SelectorConfig::load(const ConfigNode& root) {
  readMode(root, "environment", environment);
  tau_translation_m = environment == Environment::Outdoor ? 2.0 : 1.0;
  const ConfigNode n = root.section("selector");
  n.get("degeneracy_threshold", degeneracy_threshold).get("degenerate_frames", degenerate_frames);
  n.get("tau_translation_m", tau_translation_m).get("tau_rotation_deg", tau_rotation_deg);
  n.check(degeneracy_threshold >= 0 && degeneracy_threshold < 0.58, "degeneracy_threshold",
          "must be in [0, 1/sqrt(3))");
  n.check(degenerate_frames >= 1, "degenerate_frames", "must be >= 1");
  n.check(tau_translation_m > 0, "tau_translation_m", "must be > 0");
  n.check(tau_rotation_deg > 0, "tau_rotation_deg", "must be > 0");
  n.get("information_ratio", information_ratio);
  n.check(std::isfinite(information_ratio) && information_ratio >= 0, "information_ratio", "must be >= 0 (0: off)");
}

}  // namespace livo
