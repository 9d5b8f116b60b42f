#include "livo/map/visual_point.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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

void sampleBilinearGrid(const Image& gray, const double* xs, int nx, const double* ys, int ny, float* out) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  constexpr int kMaxLine = 64;
  if (gray.width < 2 || gray.height < 2 || nx > kMaxLine) {  // degenerate images, long lines: the general sampler
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        float v = 0;
        out[j * nx + i] = sampleBilinear(gray, xs[i], ys[j], v) ? v : kNaN;
      }
    return;
  }
  int x0[kMaxLine];
  double ax[kMaxLine];
  bool x_ok[kMaxLine];
  for (int i = 0; i < nx; ++i) {
    const double x = xs[i];
    x_ok[i] = x >= 0.0 && x <= gray.width - 1;
    x0[i] = x_ok[i] ? std::min(static_cast<int>(x), gray.width - 2) : 0;
    ax[i] = x - x0[i];
  }
  for (int j = 0; j < ny; ++j) {
    float* row = out + std::ptrdiff_t(j) * nx;
    const double y = ys[j];
    if (!(y >= 0.0 && y <= gray.height - 1)) {
      std::fill(row, row + nx, kNaN);
      continue;
    }
    const int y0 = std::min(static_cast<int>(y), gray.height - 2);
    const double ay = y - y0;
    const std::uint8_t* r0 = gray.data.data() + std::ptrdiff_t(y0) * gray.row_stride;
    const std::uint8_t* r1 = r0 + gray.row_stride;
    for (int i = 0; i < nx; ++i) {
      if (!x_ok[i]) {
        row[i] = kNaN;
        continue;
      }
      const int a = x0[i], b = a + 1;
      const double w = ax[i];
      row[i] = static_cast<float>((1 - ay) * ((1 - w) * r0[a] + w * r0[b]) + ay * ((1 - w) * r1[a] + w * r1[b]));
    }
  }
}

bool extractPatchPyramid(const Image& gray, const Vec2& px, PatchPyramid& out) {
  constexpr int C = PatchPyramid::kCrop;
  for (int l = 0; l < PatchPyramid::kLevels; ++l) {
    const double stride = double(1 << l);
    // Crop sample (r, c) sits at offset (c - (C-1)/2, r - (C-1)/2) level units from the centre.
    double xs[C], ys[C];
    for (int c = 0; c < C; ++c) xs[c] = px.x() + (double(c) - 0.5 * (C - 1)) * stride;
    for (int r = 0; r < C; ++r) ys[r] = px.y() + (double(r) - 0.5 * (C - 1)) * stride;
    float level[C * C];
    sampleBilinearGrid(gray, xs, C, ys, C, level);
    for (int k = 0; k < C * C; ++k) {
      if (std::isnan(level[k])) return false;
      out.set(l, k / C, k % C, level[k]);
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
