// Point colours of the viewer: by height (a perceptual rainbow from blue to red that never reaches the
// magenta of the trajectory), by intensity (gray ramp) or by the camera's colour.
#pragma once

#include <cstdint>
#include <string>

namespace livo::viewer {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
  bool operator!=(const Rgb& o) const { return !(*this == o); }
};

/// Fixed colours of the scene (lighting is off, so these are the exact pixel values on screen).
inline constexpr Rgb kTrajectoryColour{255, 0, 255};  ///< magenta: no colour map produces it
inline constexpr Rgb kScanColour{255, 255, 255};      ///< the current scan
inline constexpr Rgb kFrustumColour{255, 220, 0};
inline constexpr Rgb kMapPathColour{0, 230, 255};     ///< cyan: the loop-corrected keyframe path
inline constexpr Rgb kLoopEdgeColour{255, 40, 40};    ///< red: loop edges between keyframes
inline constexpr Rgb kUnseenColour{90, 90, 90};       ///< image mode: points no camera saw
inline constexpr Rgb kBackgroundColour{20, 20, 26};

enum class ColourMode { kHeight, kIntensity, kImage };

/// "height", "intensity", "image".
std::string colourModeName(ColourMode m);
/// Parses a name of colourModeName(); false when unknown.
bool parseColourMode(const std::string& name, ColourMode& out);
/// The next mode in the cycle height -> intensity -> image -> height, skipping intensity when
/// `have_intensity` is false (a run directory's map.pcd has none).
ColourMode nextColourMode(ColourMode m, bool have_intensity);

/// Height colour of t in [0, 1] (clamped; NaN as 0): blue (0) - cyan - green - yellow - red (1), a
/// piecewise-linear rainbow whose blue stays below 40 wherever red exceeds 128 (far from magenta).
Rgb heightColour(double t);
/// Gray of t in [0, 1] (clamped), from 40 (t = 0) to 255, so that weak returns stay visible.
Rgb intensityColour(double t);
/// 0xRRGGBB (-1 or any negative: not seen, kUnseenColour).
Rgb imageColour(std::int32_t rgb);

}  // namespace livo::viewer
