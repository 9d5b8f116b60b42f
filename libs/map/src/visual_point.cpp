#include "livo/map/visual_point.hpp"

#include <cmath>

namespace livo {

bool sampleBilinear(const Image& gray, double x, double y, float& out) {
  if (!(x >= 0.0 && y >= 0.0 && x <= gray.width - 1 && y <= gray.height - 1)) return false;
  const int x0 = std::min(static_cast<int>(x), gray.width - 2 < 0 ? 0 : gray.width - 2);
  const int y0 = std::min(static_cast<int>(y), gray.height - 2 < 0 ? 0 : gray.height - 2);
  const double ax = x - x0, ay = y - y0;
  const std::uint8_t* r0 = gray.data.data() + std::ptrdiff_t(y0) * gray.row_stride;
  const std::uint8_t* r1 = r0 + (gray.height > 1 ? gray.row_stride : 0);
  const int x1 = gray.width > 1 ? x0 + 1 : x0;
  out = static_cast<float>((1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x1]));
  return true;
}

bool extractPatchPyramid(const Image& gray, const Vec2& px, PatchPyramid& out) {
  constexpr int C = PatchPyramid::kCrop;
  for (int l = 0; l < PatchPyramid::kLevels; ++l) {
    const double stride = double(1 << l);
    for (int r = 0; r < C; ++r) {
      for (int c = 0; c < C; ++c) {
        // Crop sample (r, c) sits at offset (c - (C-1)/2, r - (C-1)/2) level units from the centre.
        const double dx = (double(c) - 0.5 * (C - 1)) * stride;
        const double dy = (double(r) - 0.5 * (C - 1)) * stride;
        if (!sampleBilinear(gray, px.x() + dx, px.y() + dy, out.at(l, r, c))) return false;
      }
    }
  }
  return true;
}

bool PatchPyramid::sample(int level, double dx, double dy, float& out) const {
  // Crop coordinates of the offset (centre at (C-1)/2).
  const double x = dx + 0.5 * (kCrop - 1);
  const double y = dy + 0.5 * (kCrop - 1);
  if (!(x >= 0.0 && y >= 0.0 && x <= kCrop - 1 && y <= kCrop - 1)) return false;
  const int x0 = std::min(static_cast<int>(x), kCrop - 2);
  const int y0 = std::min(static_cast<int>(y), kCrop - 2);
  const double ax = x - x0, ay = y - y0;
  out = static_cast<float>((1 - ay) * ((1 - ax) * at(level, y0, x0) + ax * at(level, y0, x0 + 1)) +
                           ay * ((1 - ax) * at(level, y0 + 1, x0) + ax * at(level, y0 + 1, x0 + 1)));
  return true;
}

}  // namespace livo
