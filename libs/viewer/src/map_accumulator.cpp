#include "livo/viewer/map_accumulator.hpp"

#include <cmath>
#include <stdexcept>

namespace livo::viewer {

namespace {

constexpr int kKeyBits = 21;
constexpr std::int64_t kKeyHalf = std::int64_t(1) << (kKeyBits - 1);

/// 3 x 21 bits of voxel index; false outside +-2^20 voxels (+-105 km at 0.1 m).
bool voxelKey(const Eigen::Vector3f& p, double voxel_m, std::uint64_t& key) {
  std::uint64_t k = 0;
  for (int a = 0; a < 3; ++a) {
    const double i = std::floor(double(p[a]) / voxel_m);
    if (!(i >= -double(kKeyHalf) && i < double(kKeyHalf))) return false;
    k = (k << kKeyBits) | std::uint64_t(std::int64_t(i) + kKeyHalf);
  }
  key = k;
  return true;
}

}  // namespace

MapAccumulator::MapAccumulator(const MapAccumulatorConfig& cfg) : cfg_(cfg) {
  if (!(std::isfinite(cfg_.voxel_m) && cfg_.voxel_m > 0.0))
    throw std::invalid_argument("MapAccumulatorConfig.voxel_m must be > 0");
  if (cfg_.max_points == 0) throw std::invalid_argument("MapAccumulatorConfig.max_points must be > 0");
}

void MapAccumulator::add(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& intensity,
                         const std::vector<std::int32_t>& rgb) {
  if (!intensity.empty() && intensity.size() != points.size())
    throw std::invalid_argument("MapAccumulator::add: " + std::to_string(intensity.size()) + " intensities for " +
                                std::to_string(points.size()) + " points");
  if (!rgb.empty() && rgb.size() != points.size())
    throw std::invalid_argument("MapAccumulator::add: " + std::to_string(rgb.size()) + " colours for " +
                                std::to_string(points.size()) + " points");
  bool changed = false;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    std::uint64_t key = 0;
    if (!p.allFinite() || !voxelKey(p, cfg_.voxel_m, key)) {
      ++skipped_;
      continue;
    }
    auto it = index_.find(key);
    if (it == index_.end()) {
      if (order_.size() >= cfg_.max_points) {  // evict the least recently seen voxel
        index_.erase(order_.front().key);
        order_.pop_front();
        ++evicted_;
      }
      order_.push_back(Voxel{MapPoint{}, key});
      it = index_.emplace(key, std::prev(order_.end())).first;
    } else {
      order_.splice(order_.end(), order_, it->second);  // now the most recently seen
    }
    MapPoint& m = it->second->point;
    ++m.n;
    const float w = 1.0f / float(m.n);  // running means: m += (x - m) / n
    m.p += (p - m.p) * w;
    const float in = intensity.empty() || !std::isfinite(intensity[i]) ? 0.0f : intensity[i];
    m.intensity += (in - m.intensity) * w;
    if (!rgb.empty() && rgb[i] >= 0) m.rgb = rgb[i] & 0xFFFFFF;
    changed = true;
  }
  if (changed) ++version_;
}

void MapAccumulator::clear() {
  if (order_.empty()) return;
  order_.clear();
  index_.clear();
  ++version_;
}

}  // namespace livo::viewer
