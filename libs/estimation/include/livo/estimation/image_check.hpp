// Camera failures a frame's image is checked for before the visual update may read it: the wrong
// size (not the calibrated camera), black (lens cap, dark), saturated (blinded), frozen (the driver
// repeats the last frame) and missing (no image for the frame although the camera is on). A failed
// image is counted and never used: the frame stays LiDAR-inertial.
//
// Thresholds follow the configured pixel noise sigma (camera.pixel_noise): a pixel is dark when it
// is within 3 sigma + 2 gray levels of 0, bright when within that of 255. An image is black when at
// most 5 % of its pixels are not dark, saturated when at least 80 % are bright, frozen when it is
// byte-identical to the previous image (a real sensor's noise never repeats). Pixels are sampled on
// a grid of about 4,000 for the dark / bright counts.
#pragma once

#include "livo/common/types.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

namespace livo {

enum class ImageStatus { Ok, WrongSize, Black, Saturated, Frozen, Missing };
const char* toString(ImageStatus s);

struct ImageCheckCounters {
  std::size_t wrong_size = 0, black = 0, saturated = 0, frozen = 0, missing = 0;
  void count(ImageStatus s);
};

class ImageCheck {
 public:
  explicit ImageCheck(double pixel_noise) : pixel_noise_(pixel_noise) {}
  /// Content checks of a Gray8 image (the size is the caller's check): Ok, Black, Saturated or Frozen.
  ImageStatus check(const Image& gray);

 private:
  double pixel_noise_;
  std::uint64_t last_hash_ = 0;
  bool have_last_ = false;
};

}  // namespace livo
