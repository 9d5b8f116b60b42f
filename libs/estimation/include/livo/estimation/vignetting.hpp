// Radiometric vignetting of the rig's camera (camera.vignetting: k, config/README.md): the image of a
// uniform scene falls off as 1 - k r^2, r the distance from the principal point over that of the
// farthest image corner (the simulator's model, config/sim/README.md). The photometric update compares
// a point's patches across images taken at different pixels, and only a per-image exposure factor
// separates them: a point seen at the centre and later near a corner would differ by up to k in
// brightness. The rig's k is therefore calibrated out of every image before the visual update
// (images are divided by the fall-off; results above 255 saturate); with k = 0 nothing is done.
#pragma once

#include "livo/common/types.hpp"

#include <vector>

namespace livo {

class VignettingCorrection {
 public:
  VignettingCorrection() = default;
  /// `k` in [0, 1) (CameraConfig checks it), the image size and principal point at the processing scale.
  VignettingCorrection(double k, int width, int height, double cx, double cy);

  bool active() const { return !gain_.empty(); }
  /// 1 / (1 - k r^2) at pixel (u, v).
  double gainAt(double u, double v) const;
  /// `out` = `in` (GRAY8, the configured size) corrected; `in` and `out` may be the same image.
  void apply(const Image& in, Image& out) const;

 private:
  double k_ = 0.0, cx_ = 0.0, cy_ = 0.0, inv_r2_corner_ = 0.0;
  int width_ = 0, height_ = 0;
  std::vector<float> gain_;  ///< per pixel, row-major
};

}  // namespace livo
