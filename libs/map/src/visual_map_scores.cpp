#include "livo/map/visual_map_scores.hpp"

#include <algorithm>
#include <cmath>

namespace livo {

double shiTomasiScore(const Image& gray, const Vec2& px) {
  if (gray.format != PixelFormat::Gray8 || gray.empty() || !px.allFinite()) return -1.0;
  constexpr int kHalf = PatchPyramid::kSize / 2;
  const double ux = std::round(px.x()), uy = std::round(px.y());
  // Box [u-4, u+3] plus one pixel for the central differences on each side.
  if (ux - kHalf - 1 < 0 || uy - kHalf - 1 < 0 || ux + kHalf > gray.width - 1 || uy + kHalf > gray.height - 1)
    return -1.0;
  const int x0 = int(ux) - kHalf, y0 = int(uy) - kHalf;
  const std::uint8_t* d = gray.data.data();
  const std::ptrdiff_t s = gray.row_stride;
  double a = 0.0, b = 0.0, c = 0.0;
  for (int y = y0; y < y0 + PatchPyramid::kSize; ++y) {
    const std::uint8_t* row = d + std::ptrdiff_t(y) * s;
    for (int x = x0; x < x0 + PatchPyramid::kSize; ++x) {
      const double gx = 0.5 * (double(row[x + 1]) - double(row[x - 1]));
      const double gy = 0.5 * (double(row[x + s]) - double(row[x - s]));
      a += gx * gx;
      b += gx * gy;
      c += gy * gy;
    }
  }
  const double n = double(PatchPyramid::kSize * PatchPyramid::kSize);
  a /= n;
  b /= n;
  c /= n;
  const double half_diff = 0.5 * (a - c);
  return std::max(0.0, 0.5 * (a + c) - std::sqrt(half_diff * half_diff + b * b));
}

PatchValues patchOfLevel(const PatchPyramid& pyramid, int level) {
  PatchValues out{};
  constexpr int S = PatchPyramid::kSize, M = PatchPyramid::kMargin;
  for (int r = 0; r < S; ++r)
    for (int c = 0; c < S; ++c) out[std::size_t(r * S + c)] = pyramid.at(level, r + M, c + M);
  return out;
}

double ncc(const PatchValues& a, const PatchValues& b) {
  const double n = double(a.size());
  double ma = 0.0, mb = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= n;
  mb /= n;
  double sab = 0.0, saa = 0.0, sbb = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double da = a[i] - ma, db = b[i] - mb;
    sab += da * db;
    saa += da * da;
    sbb += db * db;
  }
  // Flat patches (variance below ~1e-6 gray^2 per sample) carry no correlation.
  if (saa <= 1e-6 * n || sbb <= 1e-6 * n) return 0.0;
  return sab / std::sqrt(saa * sbb);
}

}  // namespace livo
