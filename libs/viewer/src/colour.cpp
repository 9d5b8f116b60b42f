#include "livo/viewer/colour.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace livo::viewer {

std::string colourModeName(ColourMode m) {
  switch (m) {
    case ColourMode::kHeight: return "height";
    case ColourMode::kIntensity: return "intensity";
    case ColourMode::kImage: return "image";
  }
  return "height";
}

bool parseColourMode(const std::string& name, ColourMode& out) {
  for (const ColourMode m : {ColourMode::kHeight, ColourMode::kIntensity, ColourMode::kImage})
    if (colourModeName(m) == name) {
      out = m;
      return true;
    }
  return false;
}

ColourMode nextColourMode(ColourMode m, bool have_intensity) {
  switch (m) {
    case ColourMode::kHeight: return have_intensity ? ColourMode::kIntensity : ColourMode::kImage;
    case ColourMode::kIntensity: return ColourMode::kImage;
    case ColourMode::kImage: return ColourMode::kHeight;
  }
  return ColourMode::kHeight;
}

Rgb heightColour(double t) {
  // Knots at 0, 1/4, 1/2, 3/4, 1: blue, cyan, green, yellow, red (slightly darkened ends).
  static constexpr std::array<std::array<double, 3>, 5> kKnots{{
      {{30, 60, 230}}, {{0, 200, 230}}, {{40, 210, 60}}, {{240, 220, 0}}, {{220, 30, 0}}}};
  if (!std::isfinite(t)) t = 0.0;
  const double x = std::clamp(t, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  Rgb c;
  std::uint8_t* out[3] = {&c.r, &c.g, &c.b};
  for (int k = 0; k < 3; ++k)
    *out[k] = static_cast<std::uint8_t>(std::lround(kKnots[i][k] + f * (kKnots[i + 1][k] - kKnots[i][k])));
  return c;
}

Rgb intensityColour(double t) {
  if (!std::isfinite(t)) t = 0.0;
  const auto g = static_cast<std::uint8_t>(std::lround(40.0 + 215.0 * std::clamp(t, 0.0, 1.0)));
  return {g, g, g};
}

Rgb imageColour(std::int32_t rgb) {
  if (rgb < 0) return kUnseenColour;
  return {static_cast<std::uint8_t>((rgb >> 16) & 0xFF), static_cast<std::uint8_t>((rgb >> 8) & 0xFF),
          static_cast<std::uint8_t>(rgb & 0xFF)};
}

}  // namespace livo::viewer
