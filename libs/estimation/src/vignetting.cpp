#include "livo/estimation/vignetting.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace livo {

VignettingCorrection::VignettingCorrection(double k, int width, int height, double cx, double cy)
    : k_(k), cx_(cx), cy_(cy), width_(width), height_(height) {
  if (!(k >= 0.0 && k < 1.0)) throw std::invalid_argument("camera.vignetting: must be in [0, 1)");
  if (k == 0.0 || width <= 0 || height <= 0) return;
  double r2 = 0.0;
  for (double u : {0.0, double(width - 1)})
    for (double v : {0.0, double(height - 1)}) r2 = std::max(r2, (u - cx) * (u - cx) + (v - cy) * (v - cy));
  inv_r2_corner_ = 1.0 / std::max(r2, 1e-12);
  gain_.resize(std::size_t(width) * std::size_t(height));
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) gain_[std::size_t(v) * std::size_t(width) + std::size_t(u)] = float(gainAt(u, v));
}

double VignettingCorrection::gainAt(double u, double v) const {
  const double r2 = ((u - cx_) * (u - cx_) + (v - cy_) * (v - cy_)) * inv_r2_corner_;
  return 1.0 / (1.0 - k_ * r2);
}

void VignettingCorrection::apply(const Image& in, Image& out) const {
  if (in.width != width_ || in.height != height_ || in.format != PixelFormat::Gray8)
    throw std::invalid_argument("vignetting correction: image is not GRAY8 of the calibrated size");
  if (&in != &out) {
    out.utime = in.utime;
    out.width = in.width;
    out.height = in.height;
    out.format = in.format;
    out.exposure_time_s = in.exposure_time_s;
    out.row_stride = in.width;
    out.data.resize(std::size_t(in.width) * std::size_t(in.height));
  }
  for (int v = 0; v < height_; ++v) {
    const std::uint8_t* src = in.data.data() + std::size_t(v) * std::size_t(in.row_stride);
    std::uint8_t* dst = out.data.data() + std::size_t(v) * std::size_t(out.row_stride);
    const float* g = gain_.data() + std::size_t(v) * std::size_t(width_);
    for (int u = 0; u < width_; ++u) dst[u] = std::uint8_t(std::min(255.f, float(src[u]) * g[u] + 0.5f));
  }
}

}  // namespace livo
