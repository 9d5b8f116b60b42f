// The viewer's map: every drawn scan's world points in a voxel grid, one point per voxel (the mean of
// the points that fell in it, their mean intensity and the latest camera colour), bounded in voxels.
// When full, the voxel seen least recently is evicted, so a long drive shows the most recent part of
// the map instead of freezing at its start (map.pcd of livo-exporter keeps the first voxels instead:
// a file must not change its past). Insertion and eviction are O(1) per point.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <list>
#include <unordered_map>
#include <vector>

namespace livo::viewer {

struct MapAccumulatorConfig {
  double voxel_m = 0.1;                ///< voxel edge, m
  std::size_t max_points = 400'000;    ///< voxels kept (points drawn), > 0
};

/// One voxel's point.
struct MapPoint {
  Eigen::Vector3f p = Eigen::Vector3f::Zero();  ///< mean of its points, world frame, m
  float intensity = 0.f;                        ///< mean intensity
  std::int32_t rgb = -1;                        ///< latest camera colour 0xRRGGBB, -1: never seen
  std::uint32_t n = 0;                          ///< points that fell in the voxel
};

class MapAccumulator {
 public:
  /// Throws std::invalid_argument for voxel_m <= 0 or max_points == 0.
  explicit MapAccumulator(const MapAccumulatorConfig& cfg);

  /// Adds points (world frame). `intensity`: empty or one per point; `rgb`: empty or one per point
  /// (0xRRGGBB, -1: not seen). Non-finite points are skipped (counted). Throws std::invalid_argument
  /// when a non-empty intensity / rgb has another size than `points`.
  void add(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& intensity,
           const std::vector<std::int32_t>& rgb);
  void clear();

  std::size_t size() const { return order_.size(); }
  /// Calls f(const MapPoint&) for every voxel, from the least to the most recently seen.
  template <class F>
  void forEach(F&& f) const {
    for (const Voxel& v : order_) f(v.point);
  }
  /// Changes with every add() / clear() that changed something (redraw when it differs).
  std::uint64_t version() const { return version_; }
  std::uint64_t evicted() const { return evicted_; }     ///< voxels evicted by max_points
  std::uint64_t skipped() const { return skipped_; }     ///< non-finite or out-of-range points
  const MapAccumulatorConfig& config() const { return cfg_; }

 private:
  struct Voxel {
    MapPoint point;
    std::uint64_t key = 0;
  };
  MapAccumulatorConfig cfg_;
  std::list<Voxel> order_;  // least recently seen first
  std::unordered_map<std::uint64_t, std::list<Voxel>::iterator> index_;
  std::uint64_t version_ = 0, evicted_ = 0, skipped_ = 0;
};

}  // namespace livo::viewer
