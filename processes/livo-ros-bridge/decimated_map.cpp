#include "decimated_map.hpp"

#include <cmath>

namespace livo_bridge {

DecimatedMap::DecimatedMap(double voxel_m, std::int64_t max_points) : voxel_(voxel_m), max_points_(max_points) {}

std::uint64_t DecimatedMap::key(float x, float y, float z) const {
  // 21 bits per axis around the origin: +-2^20 voxels (+-210 km at 0.2 m); beyond, keys wrap (the map
  // merges far-away voxels, never fails).
  auto axis = [&](float v) {
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v / voxel_)) + (1 << 20)) & 0x1FFFFF;
  };
  return axis(x) << 42 | axis(y) << 21 | axis(z);
}

void DecimatedMap::add(std::size_t n, const float* x, const float* y, const float* z, const float* intensity,
                       const std::int32_t* rgb) {
  if (rgb) coloured_ = true;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]) || !std::isfinite(z[i])) continue;
    const auto [it, fresh] = index_.emplace(key(x[i], y[i], z[i]), static_cast<std::uint32_t>(x_.size()));
    if (!fresh) continue;
    x_.push_back(x[i]);
    y_.push_back(y[i]);
    z_.push_back(z[i]);
    intensity_.push_back(intensity[i]);
    rgb_.push_back(rgb ? rgb[i] : -1);
  }
  while (static_cast<std::int64_t>(x_.size()) > max_points_) coarsen();
}

void DecimatedMap::coarsen() {
  voxel_ *= 2;
  index_.clear();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < x_.size(); ++i) {
    if (!index_.emplace(key(x_[i], y_[i], z_[i]), static_cast<std::uint32_t>(kept)).second) continue;
    x_[kept] = x_[i], y_[kept] = y_[i], z_[kept] = z_[i];
    intensity_[kept] = intensity_[i], rgb_[kept] = rgb_[i];
    ++kept;
  }
  for (auto* v : {&x_, &y_, &z_, &intensity_}) v->resize(kept);
  rgb_.resize(kept);
}

}  // namespace livo_bridge
