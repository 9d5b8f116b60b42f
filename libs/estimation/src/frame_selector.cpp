#include "livo/estimation/frame_selector.hpp"

#include <cmath>
#include <stdexcept>

namespace livo {

VisualMode parseVisualMode(const std::string& s) {
  if (s == "adaptive") return VisualMode::Adaptive;
  if (s == "all") return VisualMode::All;
  if (s == "off") return VisualMode::Off;
  throw std::invalid_argument("visual mode must be adaptive, all or off (got '" + s + "')");
}

double FrameSelector::translationThreshold(double sigma_min) const {
  return std::sqrt(3.0) * sigma_min * cfg_.tau_translation_m;
}

double FrameSelector::rotationThreshold(double sigma_min) const {
  return std::sqrt(3.0) * sigma_min * cfg_.tau_rotation_deg * M_PI / 180.0;
}

bool FrameSelector::select(const NavState& x, double sigma_min, bool degenerate) const {
  switch (mode_) {
    case VisualMode::Off: return false;
    case VisualMode::All: return true;
    case VisualMode::Adaptive: break;
  }
  if (degenerate || !have_last_) return true;
  const double dt = (x.p_world_imu - last_.p_world_imu).norm();
  const double dr = rotationAngle(last_.R_world_imu.transpose() * x.R_world_imu);
  return dt > translationThreshold(sigma_min) || dr > rotationThreshold(sigma_min);
}

void FrameSelector::markUsed(const NavState& x) {
  last_ = x;
  have_last_ = true;
}

}  // namespace livo
