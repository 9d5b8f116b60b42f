// Visual map points: LiDAR points that carry small patch pyramids from the images that saw them
// (docs/algorithms.md sections 4-5). Unlike the reference code, an observation never keeps a whole image
// alive: it stores one small crop per pyramid level (section 8, "Memory" 1).
#pragma once

#include "livo/common/so3.hpp"
#include "livo/common/types.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace livo {

using Vec2 = Eigen::Vector2d;

/// Patch pyramid of one observation. Level l samples the full-resolution image (bilinear) on a grid of
/// stride 2^l pixels centred on the point's pixel: the patch proper is kSize x kSize samples, and the
/// crop keeps kMargin extra samples on every side so that a reference patch can be resampled under a
/// moderate affine warp without the original image.
/// Storage: one byte per sample, the bilinear value rounded to the nearest gray level (the images are
/// 8-bit: the rounding adds at most half a gray level, a variance of 1/12 against the pixel noise's),
/// 432 bytes per pyramid instead of 1728 as floats: the visual maps' patches are most of their bytes.
struct PatchPyramid {
  static constexpr int kLevels = 3;
  static constexpr int kSize = 8;    ///< patch side, samples
  static constexpr int kMargin = 2;  ///< extra samples per side for warping
  static constexpr int kCrop = kSize + 2 * kMargin;  ///< crop side, samples (12)
  static constexpr int kCropValues = kCrop * kCrop;
  static constexpr int kValues = kLevels * kCropValues;  ///< 432
  std::array<std::uint8_t, kValues> values{};  ///< level-major, row-major gray values

  float at(int level, int row, int col) const { return float(values[index(level, row, col)]); }
  /// Stores `v` rounded to the nearest gray level, clamped to [0, 255] (NaN stores 0).
  void set(int level, int row, int col, float v) { values[index(level, row, col)] = quantize(v); }
  /// A sample a patch can hold: a gray value in [0, 255] up to rounding (NaN is not).
  static bool isGrayValue(float v) { return v >= -0.5f && v <= 255.5f; }
  static std::uint8_t quantize(float v) {
    if (!(v > 0.f)) return 0;
    return v >= 254.5f ? std::uint8_t(255) : static_cast<std::uint8_t>(v + 0.5f);
  }
  /// Bilinear sample at a position in level-`level` sample units relative to the crop centre (the
  /// point's pixel); false when it falls outside the crop.
  bool sample(int level, double dx, double dy, float& out) const;

 private:
  static std::size_t index(int level, int row, int col) { return std::size_t(level * kCropValues + row * kCrop + col); }
};

/// Sample offsets of the patch proper in level units: -kSize/2 + 0.5 ... kSize/2 - 0.5 (centred).
inline double patchOffset(int i) { return double(i) - 0.5 * double(PatchPyramid::kSize - 1); }

/// Fills `out` from a GRAY8 image around pixel `px` (level-0 pixel coordinates, pixel centres at
/// integers). Returns false when any sample of any level would read outside the image.
bool extractPatchPyramid(const Image& gray, const Vec2& px, PatchPyramid& out);
/// Bilinear gray value at `px`; false outside [0, w-1] x [0, h-1].
bool sampleBilinear(const Image& gray, double x, double y, float& out);
/// sampleBilinear at every (xs[i], ys[j]) into out[j * nx + i] (NaN outside the image), bit for bit, with
/// the column and row parts (index, weight, bounds) computed once per line: for patch grids.
void sampleBilinearGrid(const Image& gray, const double* xs, int nx, const double* ys, int ny, float* out);

/// One stored observation of a visual point.
struct VisualObservation {
  Utime utime = 0;
  PatchPyramid patch;
  Pose T_world_camera = Pose::Identity();  ///< camera pose at capture
  Vec2 px = Vec2::Zero();                  ///< pixel of the point in that image (level 0)
  float inv_exposure = 1.f;                ///< tau of that image
  float score = 0.f;                       ///< reference score (mean |NCC| + view cosine)
};

/// A visual map point.
struct VisualPoint {
  std::int64_t id = 0;
  Vec3 p_world = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();   ///< unit normal facing the cameras (from the LiDAR plane)
  Mat3 cov = Mat3::Zero();       ///< position covariance, m^2
  std::vector<VisualObservation> obs;  ///< newest last
  int reference = -1;            ///< index into obs of the reference patch (-1: none)
  bool converged = false;        ///< normal converged: only the reference is kept
  int bad_updates = 0;           ///< consecutive updates with a high photometric error
  /// Observations ever stored (obs may hold fewer: dropped beyond max_observations, only the reference
  /// kept once converged or in the long-term map); map.longterm_min_observations judges this count.
  std::int32_t views = 0;
  /// views, or the observations held where that is more (a point built without counting them).
  std::int32_t viewCount() const { return std::max(views, static_cast<std::int32_t>(obs.size())); }
  /// Moved to the long-term visual map at least once (held there now, or back in the local map after a
  /// revisit): what the long-term map kept alive (VisualStep's n_longterm_used counts these).
  bool from_longterm = false;
  Utime last_seen = 0;

  const VisualObservation* referenceObs() const {
    return reference >= 0 && reference < int(obs.size()) ? &obs[std::size_t(reference)] : nullptr;
  }
  /// Heap + inline bytes of this point (for the map's memory accounting).
  std::size_t bytes() const { return sizeof(VisualPoint) + obs.capacity() * sizeof(VisualObservation); }
};

}  // namespace livo
