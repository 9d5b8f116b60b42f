#include "livo/common/types.hpp"

#include <cmath>

namespace livo {

Utime LidarScan::endUtime() const {
  float last = 0.f;
  for (const auto& p : points) last = std::max(last, p.time_offset_s);
  return utime + fromSeconds(last);
}

int bytesPerPixel(PixelFormat f) {
  switch (f) {
    case PixelFormat::Gray8: return 1;
    case PixelFormat::Rgb8:
    case PixelFormat::Bgr8: return 3;
    case PixelFormat::Gray16: return 2;
    case PixelFormat::Jpeg:
    case PixelFormat::Png: return 0;
  }
  return 0;
}

const char* toString(PixelFormat f) {
  switch (f) {
    case PixelFormat::Gray8: return "GRAY8";
    case PixelFormat::Rgb8: return "RGB8";
    case PixelFormat::Bgr8: return "BGR8";
    case PixelFormat::Jpeg: return "JPEG";
    case PixelFormat::Png: return "PNG";
    case PixelFormat::Gray16: return "GRAY16";
  }
  return "UNKNOWN";
}

}  // namespace livo
