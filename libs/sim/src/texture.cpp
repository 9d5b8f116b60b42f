#include "livo/sim/texture.hpp"

#include "livo/sim/random.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace livo::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// 16 unit gradient directions.
struct NoiseTables {
  std::array<std::array<double, 2>, 16> grad{};
  std::array<std::uint8_t, 512> perm{};  ///< a permutation of 0..255, repeated (Perlin's hash)
  std::array<std::array<double, 2>, 12> octave_rot{};  ///< cos, sin of each octave's rotation
  NoiseTables() {
    for (int k = 0; k < 16; ++k) grad[k] = {std::cos(k * kPi / 8.0 + 0.1), std::sin(k * kPi / 8.0 + 0.1)};
    std::array<int, 256> p{};
    for (int i = 0; i < 256; ++i) p[i] = i;
    SplitMix rng(0x5EED);
    for (int i = 255; i > 0; --i) std::swap(p[i], p[rng.next() % static_cast<std::uint64_t>(i + 1)]);
    for (int i = 0; i < 512; ++i) perm[i] = static_cast<std::uint8_t>(p[i & 255]);
    for (int k = 0; k < 12; ++k) octave_rot[k] = {std::cos(0.9 * k), std::sin(0.9 * k)};
  }
};
const NoiseTables& tables() {
  static const NoiseTables t;
  return t;
}

inline std::int64_t fastFloor(double x) {
  const auto i = static_cast<std::int64_t>(x);
  return x < static_cast<double>(i) ? i - 1 : i;
}

inline double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

// Smoothstep from e0 to e0 + 1 / inv_width (the caller precomputes the inverse width: no division).
inline double smoothRamp(double x, double e0, double inv_width) {
  const double t = std::clamp((x - e0) * inv_width, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// Weight of a feature of wavelength `lambda` seen with footprint 1 / inv_fp: 1 above 3 footprints,
// fading to 0 at 2 footprints (Nyquist: a feature needs two samples per wavelength).
inline double octaveWeight(double lambda, double inv_fp) { return std::clamp(lambda * inv_fp - 2.0, 0.0, 1.0); }

}  // namespace

namespace {

inline double noise2(double x, double y, std::uint64_t seed) {
  const std::int64_t ix = fastFloor(x), iy = fastFloor(y);
  const double dx = x - static_cast<double>(ix), dy = y - static_cast<double>(iy);
  const NoiseTables& tb = tables();
  // Lattice hash: Perlin's permutation table, shifted per seed (period 256 cells).
  const auto sx = static_cast<std::int64_t>(seed & 255u), sy = static_cast<std::int64_t>((seed >> 8) & 255u);
  const int x0 = static_cast<int>((ix + sx) & 255), y0 = static_cast<int>((iy + sy) & 255);
  const int a = tb.perm[x0], b = tb.perm[x0 + 1];
  auto corner = [&](int h, double px, double py) {
    const auto& d = tb.grad[h & 15];
    return d[0] * px + d[1] * py;
  };
  const double n00 = corner(tb.perm[a + y0], dx, dy);
  const double n10 = corner(tb.perm[b + y0], dx - 1.0, dy);
  const double n01 = corner(tb.perm[a + y0 + 1], dx, dy - 1.0);
  const double n11 = corner(tb.perm[b + y0 + 1], dx - 1.0, dy - 1.0);
  const double u = fade(dx), v = fade(dy);
  const double p = n00 + u * (n10 - n00);
  const double q = n01 + u * (n11 - n01);
  return p + v * (q - p);
}

// Shade offset of the rectangle pattern at (x, y) (see noiseAlbedo); inv_cell = 1 / cell size.
double rectangles(double x, double y, double fp, double inv_cell, std::uint64_t seed) {
  const double xs = x * inv_cell, ys = y * inv_cell;
  const std::int64_t cx = fastFloor(xs), cy = fastFloor(ys);
  const std::uint64_t h = mix64(seed ^ (static_cast<std::uint64_t>(cx) * 0x9E3779B97F4A7C15ull) ^
                                (static_cast<std::uint64_t>(cy) * 0xC2B2AE3D27D4EB4Full));
  if ((h & 0xFF) >= 102) return 0.0;  // 40% of the cells
  auto unit = [&](int k) { return static_cast<double>((h >> (8 + 10 * k)) & 1023u) * (1.0 / 1023.0); };
  const double x0 = 0.05 + 0.4 * unit(0), x1 = x0 + 0.2 + 0.35 * unit(1);
  const double y0 = 0.05 + 0.4 * unit(2), y1 = y0 + 0.2 + 0.35 * unit(3);
  const double shade = (unit(4) < 0.5 ? -1.0 : 1.0) * (0.15 + 0.2 * unit(5));
  const double w = std::max(fp * inv_cell, 1e-4);  // edge half-width in cell units
  if (w > 0.25) return shade * (x1 - x0) * (y1 - y0) * 0.4;  // mean over cells
  const double u = xs - static_cast<double>(cx), v = ys - static_cast<double>(cy);
  const double iw = 0.5 / w;
  const double inside = smoothRamp(u, x0 - w, iw) * (1.0 - smoothRamp(u, x1 - w, iw)) * smoothRamp(v, y0 - w, iw) *
                        (1.0 - smoothRamp(v, y1 - w, iw));
  return shade * inside;
}

}  // namespace

double gradientNoise(double x, double y, std::uint64_t seed) { return noise2(x, y, seed); }

TextureBank::TextureBank(TextureKind kind, const std::vector<std::string>& image_paths, double scale_m, double tile_m)
    : kind_(kind),
      scale_m_(scale_m),
      tile_m_(tile_m),
      inv_blob_cell_(1.0 / (0.8 * scale_m)),
      inv_spot_cell_(1.0 / (0.15 * scale_m)),
      inv_rect_cell_(1.0 / (0.6 * scale_m)) {
  if (kind_ != TextureKind::Images) return;
  for (const auto& path : image_paths) {
    const cv::Mat img = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (img.empty()) throw std::runtime_error(path + ": cannot read texture image");
    if (img.cols < 2 || img.rows < 2) throw std::runtime_error(path + ": texture image is too small");
    std::vector<float> data(static_cast<std::size_t>(img.cols) * img.rows);
    for (int r = 0; r < img.rows; ++r)
      for (int c = 0; c < img.cols; ++c) data[static_cast<std::size_t>(r) * img.cols + c] = img.at<std::uint8_t>(r, c) / 255.f;
    images_.push_back(buildMip(img.cols, img.rows, std::move(data)));
  }
}

SurfaceStyle TextureBank::makeStyle(std::uint64_t seed, std::uint64_t surface_id) const {
  SplitMix rng(hashKeys(seed, static_cast<std::uint64_t>(RngStream::Texture), surface_id));
  SurfaceStyle s;
  s.base = rng.uniform(0.35, 0.65);
  s.contrast = rng.uniform(0.6, 1.0);
  const double a = rng.uniform(0.0, 2.0 * kPi);
  s.cos_a = std::cos(a);
  s.sin_a = std::sin(a);
  s.offset_u = rng.uniform(-1000.0, 1000.0);
  s.offset_v = rng.uniform(-1000.0, 1000.0);
  s.noise_seed = rng.next();
  s.image = images_.empty() ? 0 : static_cast<int>(rng.next() % images_.size());
  if (kind_ == TextureKind::None) s.base = rng.uniform(0.25, 0.8);
  return s;
}

double TextureBank::albedo(const SurfaceStyle& s, double u, double v, double footprint_m) const {
  switch (kind_) {
    case TextureKind::None: return s.base;
    case TextureKind::Images: return imageAlbedo(s, u, v, footprint_m);
    case TextureKind::Noise: break;
  }
  return noiseAlbedo(s, u, v, footprint_m);
}

double TextureBank::noiseAlbedo(const SurfaceStyle& s, double u, double v, double footprint_m) const {
  const double fp = std::max(footprint_m, 1e-4);
  const double x = s.cos_a * u - s.sin_a * v + s.offset_u;
  const double y = s.sin_a * u + s.cos_a * v + s.offset_v;

  // Fractal noise: octave k has wavelength scale / 2^k and amplitude 0.65^k (close to the 1/f spectrum
  // of natural images); each octave is rotated so that lattice directions do not line up.
  const double inv_fp = 1.0 / fp;
  double fbm = 0.0, amp = 1.0, lambda = scale_m_, inv_lambda = 1.0 / scale_m_;
  const auto& rot = tables().octave_rot;
  for (int k = 0; k < 12; ++k) {
    const double w = octaveWeight(lambda, inv_fp);
    if (w <= 0.0) break;
    const double c = rot[k][0] * inv_lambda, sn = rot[k][1] * inv_lambda;
    fbm += w * amp * noise2(c * x - sn * y, sn * x + c * y, s.noise_seed + 977 * k);
    amp *= 0.65;
    lambda *= 0.5;
    inv_lambda *= 2.0;
  }

  // Blobs with sharp edges (regions of another shade), widened to the footprint: the noise changes by
  // about 1 per lattice cell, so an edge of width fp spans fp / cell in noise units.
  const double blob_inv = inv_blob_cell_;
  const double nb = noise2(x * blob_inv, y * blob_inv, s.noise_seed + 40503) +
                    0.5 * noise2(2.0 * x * blob_inv, 2.0 * y * blob_inv, s.noise_seed + 21011);
  const double wb = std::max(0.01, 1.5 * fp * blob_inv);
  const double region = smoothRamp(nb - 0.08, -wb, 0.5 / wb);

  // Small dark spots (faded to their mean once smaller than the footprint).
  const double spot_inv = inv_spot_cell_;
  const double ws = std::max(0.01, 1.5 * fp * spot_inv);
  const double spot =
      ws < 0.5 ? smoothRamp(noise2(x * spot_inv, y * spot_inv, s.noise_seed + 5003) - 0.3, -ws, 0.5 / ws) : 0.1;

  // Rectangles with straight edges and corners (posters, panels, tiles): in a grid of cells of
  // 0.6 scale, 40% of the cells hold a rectangle of random extent and shade. Edges are smoothed over
  // the footprint; once the footprint reaches a quarter cell the rectangle fades to its mean.
  const double rect = rectangles(x, y, fp, inv_rect_cell_, s.noise_seed + 7919);

  const double a = s.base + s.contrast * (0.45 * fbm + 0.28 * (region - 0.5) - 0.22 * spot + rect);
  return std::clamp(a, 0.03, 0.97);
}

double TextureBank::imageAlbedo(const SurfaceStyle& s, double u, double v, double footprint_m) const {
  const MipImage& img = images_[static_cast<std::size_t>(s.image)];
  const double texel = tile_m_ / img.levels[0].width;  // metres per level-0 pixel
  const double x = (s.cos_a * u - s.sin_a * v + s.offset_u) / texel;
  const double y = (s.sin_a * u + s.cos_a * v + s.offset_v) / texel;
  const double level = std::log2(std::max(footprint_m / texel, 1.0));
  return 0.04 + 0.92 * sampleMip(img, x, y, level);
}

MipImage TextureBank::buildMip(int width, int height, std::vector<float> data) {
  MipImage m;
  m.levels.push_back({width, height, std::move(data)});
  while (m.levels.back().width > 1 && m.levels.back().height > 1) {
    const auto& p = m.levels.back();
    MipImage::Level l;
    l.width = p.width / 2;
    l.height = p.height / 2;
    l.data.resize(static_cast<std::size_t>(l.width) * l.height);
    for (int r = 0; r < l.height; ++r)
      for (int c = 0; c < l.width; ++c) {
        const auto at = [&](int rr, int cc) { return p.data[static_cast<std::size_t>(rr) * p.width + cc]; };
        l.data[static_cast<std::size_t>(r) * l.width + c] =
            0.25f * (at(2 * r, 2 * c) + at(2 * r, 2 * c + 1) + at(2 * r + 1, 2 * c) + at(2 * r + 1, 2 * c + 1));
      }
    m.levels.push_back(std::move(l));
  }
  return m;
}

namespace {

// Mirrored repeat: ... 2 1 0 | 0 1 2 ... n-1 | n-1 n-2 ...
inline int mirrorIndex(std::int64_t i, int n) {
  const std::int64_t period = 2 * static_cast<std::int64_t>(n);
  std::int64_t m = i % period;
  if (m < 0) m += period;
  return static_cast<int>(m < n ? m : period - 1 - m);
}

double bilinear(const MipImage::Level& l, double x, double y) {
  const double xs = x - 0.5, ys = y - 0.5;  // pixel centres at +0.5
  const double fx = std::floor(xs), fy = std::floor(ys);
  const double ax = xs - fx, ay = ys - fy;
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const int x0 = mirrorIndex(ix, l.width), x1 = mirrorIndex(ix + 1, l.width);
  const int y0 = mirrorIndex(iy, l.height), y1 = mirrorIndex(iy + 1, l.height);
  const auto at = [&](int r, int c) { return static_cast<double>(l.data[static_cast<std::size_t>(r) * l.width + c]); };
  const double top = at(y0, x0) + ax * (at(y0, x1) - at(y0, x0));
  const double bot = at(y1, x0) + ax * (at(y1, x1) - at(y1, x0));
  return top + ay * (bot - top);
}

}  // namespace

double TextureBank::sampleMip(const MipImage& img, double x, double y, double level) {
  const int top = static_cast<int>(img.levels.size()) - 1;
  level = std::clamp(level, 0.0, static_cast<double>(top));
  const int l0 = std::min(static_cast<int>(level), top);
  const int l1 = std::min(l0 + 1, top);
  const double f = level - l0;
  // Level l has pixels 2^l times larger (sizes are floored, so scale each axis by its own ratio).
  const auto& a = img.levels[static_cast<std::size_t>(l0)];
  const auto& b = img.levels[static_cast<std::size_t>(l1)];
  const double w0 = img.levels[0].width, h0 = img.levels[0].height;
  const double va = bilinear(a, x * a.width / w0, y * a.height / h0);
  if (f <= 0.0 || l1 == l0) return va;
  const double vb = bilinear(b, x * b.width / w0, y * b.height / h0);
  return va + f * (vb - va);
}

}  // namespace livo::sim
