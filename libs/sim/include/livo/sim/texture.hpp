// Surface textures of the simulated world: albedo in [0, 1] as a function of surface coordinates.
//
// - noise: procedural and natural-image-like: fractal gradient noise with a 1/f amplitude spectrum,
//   plus large blobs with sharp edges, small dark spots and scattered rectangles (straight edges and
//   corners). Octaves finer than about two footprints
//   are faded out, and edges are widened to the footprint, so that a ray per pixel does not alias.
// - images: photos tiled (mirrored) over the surface, sampled trilinearly from a mip pyramid chosen
//   by the footprint.
// - none: one constant albedo per surface (textureless).
// Every surface has its own style (offset, rotation, brightness, photo) drawn from the seed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace livo::sim {

/// Per-surface parameters of a texture, drawn once from the seed.
struct SurfaceStyle {
  double base = 0.5;      ///< mean albedo
  double contrast = 0.35;
  double cos_a = 1.0, sin_a = 0.0;  ///< rotation of the texture on the surface
  double offset_u = 0.0, offset_v = 0.0;  ///< metres
  std::uint64_t noise_seed = 0;
  int image = 0;          ///< photo index (texture: images)
};

enum class TextureKind { Noise, Images, None };

/// One gray image as a mip pyramid of floats in [0, 1].
struct MipImage {
  struct Level {
    int width = 0, height = 0;
    std::vector<float> data;
  };
  std::vector<Level> levels;  ///< levels[0] is the full resolution
};

class TextureBank {
 public:
  TextureBank() = default;
  /// `image_paths` are loaded (gray) when kind == Images; throws std::runtime_error naming the file
  /// that cannot be read. `scale_m`: noise coarsest wavelength; `tile_m`: metres per photo width.
  TextureBank(TextureKind kind, const std::vector<std::string>& image_paths, double scale_m, double tile_m);

  /// A surface style for surface `surface_id` of a world with seed `seed`.
  SurfaceStyle makeStyle(std::uint64_t seed, std::uint64_t surface_id) const;

  /// Albedo at surface coordinates (u, v) in metres, averaged over a footprint of `footprint_m`.
  double albedo(const SurfaceStyle& style, double u, double v, double footprint_m) const;

  TextureKind kind() const { return kind_; }
  std::size_t numImages() const { return images_.size(); }

  /// Builds a mip pyramid from gray values in [0, 1] (row-major), exposed for tests.
  static MipImage buildMip(int width, int height, std::vector<float> data);
  /// Trilinear lookup with mirrored tiling; (x, y) in level-0 pixels, `level` fractional.
  static double sampleMip(const MipImage& img, double x, double y, double level);

 private:
  double noiseAlbedo(const SurfaceStyle& s, double u, double v, double footprint_m) const;
  double imageAlbedo(const SurfaceStyle& s, double u, double v, double footprint_m) const;

  TextureKind kind_ = TextureKind::Noise;
  double scale_m_ = 1.0;
  double tile_m_ = 2.0;
  double inv_blob_cell_ = 1.0 / 0.8, inv_spot_cell_ = 1.0 / 0.15, inv_rect_cell_ = 1.0 / 0.6;  ///< 1 / cell sizes
  std::vector<MipImage> images_;
};

/// 2D gradient noise (Perlin 2002 with quintic fade), range about [-0.7, 0.7]; exposed for tests.
double gradientNoise(double x, double y, std::uint64_t seed);

}  // namespace livo::sim
