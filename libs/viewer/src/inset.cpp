#include "livo/viewer/inset.hpp"

#include <stdexcept>

namespace livo::viewer {

Image shrinkGray8(const Image& gray, int max_width) {
  if (max_width < 1) throw std::invalid_argument("shrinkGray8: max_width must be >= 1");
  if (gray.format != PixelFormat::Gray8) throw std::invalid_argument("shrinkGray8: not a Gray8 image");
  const int stride = gray.row_stride > 0 ? gray.row_stride : gray.width;
  if (gray.width <= 0 || gray.height <= 0 || stride < gray.width ||
      gray.data.size() < std::size_t(stride) * std::size_t(gray.height - 1) + std::size_t(gray.width))
    throw std::invalid_argument("shrinkGray8: image buffer smaller than its size");
  const int f = (gray.width + max_width - 1) / max_width;
  Image out;
  out.utime = gray.utime;
  out.format = PixelFormat::Gray8;
  out.width = gray.width / f;
  out.height = gray.height / f;
  out.row_stride = out.width;
  out.data.resize(std::size_t(out.width) * std::size_t(out.height));
  for (int v = 0; v < out.height; ++v)
    for (int u = 0; u < out.width; ++u) {
      unsigned sum = 0;
      for (int dv = 0; dv < f; ++dv)
        for (int du = 0; du < f; ++du) sum += gray.data[std::size_t(v * f + dv) * stride + std::size_t(u * f + du)];
      out.data[std::size_t(v) * out.width + u] = static_cast<std::uint8_t>((sum + unsigned(f * f) / 2) / unsigned(f * f));
    }
  return out;
}

}  // namespace livo::viewer
