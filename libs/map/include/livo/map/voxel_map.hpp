// LiDAR voxel plane map (docs/algorithms.md sections 2, 3 and 8): a hash of root voxels, each the root of
// an octree of planes with uncertainty, built and updated incrementally from world points with
// covariances, and searched for the most probable plane of a query point.
//
// Thread safety: const member functions (findBestPlane, stats, forEachPlane, ...) may run
// concurrently with each other; anything that modifies the map (insert, remove*) needs exclusive
// access. Plane pointers returned by findBestPlane stay valid until the next modification.
#pragma once

#include "livo/map/plane.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/map/voxel_key.hpp"
#include "livo/map/voxel_map_config.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <ostream>
#include <memory>
#include <unordered_map>
#include <vector>

namespace livo {

class OctreeNode;

/// Counts and memory of the map (one full walk of all octrees).
struct VoxelMapStats {
  std::size_t root_voxels = 0;
  std::size_t nodes = 0;          ///< octree nodes including the roots
  std::size_t planes = 0;         ///< plane leaves
  std::size_t frozen_leaves = 0;  ///< leaves that reached max_points (points freed)
  std::size_t stored_points = 0;  ///< points still held by leaves that can update
  std::size_t bytes = 0;          ///< estimate, see VoxelMap::bytes()
};

class VoxelMap : public PlaneFinder {
 public:
  explicit VoxelMap(VoxelMapConfig config = {});
  ~VoxelMap() override;
  VoxelMap(VoxelMap&&) noexcept;
  VoxelMap& operator=(VoxelMap&&) noexcept;
  VoxelMap(const VoxelMap&) = delete;
  VoxelMap& operator=(const VoxelMap&) = delete;

  /// Builds and updates the map in one: each point goes to its root voxel (created when new) and
  /// descends the octree (docs/algorithms.md section 3). Points with non-finite coordinates or beyond
  /// |p| / voxel_size >= 2^52 are skipped. Returns the number of points taken.
  std::size_t insert(const std::vector<PointWithCov>& points);

  using PlaneMatch = livo::PlaneMatch;
  /// findBestPlane (PlaneFinder, docs/algorithms.md section 2, "Association"): every plane leaf of the
  /// point's root voxel is a candidate when the in-plane distance
  /// sqrt(|p - q|^2 - d^2) <= sigma_num * radius and |d| < sigma_num * sqrt(sigma_l), with
  /// sigma_l = J Sigma_nq J^T + n^T Sigma_w n, J = [(p - q)^T, -n^T]; the highest
  /// sigma_l^-1/2 exp(-d^2 / 2 sigma_l) wins. If none is accepted (or the voxel does not exist), ONE
  /// neighbour root voxel is tried: step +1 along each axis where the point lies in the upper
  /// quarter of its voxel ((p/s - floor(p/s)) > 0.75), -1 where it lies in the lower quarter (< 0.25).
  using PlaneFinder::findBestPlane;
  double rootVoxelSize() const override { return config_.voxel_size_m; }
  double sigmaNum() const override { return config_.sigma_num; }
  void visitPlanes(const VoxelKey& key, const std::function<void(const Plane&)>& f) const override;

  /// The neighbour key findBestPlane tries for `p`; false when p is in no outer quarter.
  bool neighbourKey(const Vec3& p, VoxelKey& out) const;
  VoxelKey keyOf(const Vec3& p) const { return VoxelKey::fromPoint(p, config_.voxel_size_m); }

  std::size_t numRootVoxels() const { return roots_.size(); }
  std::size_t numPlanes() const;
  /// Memory estimate in bytes: hash buckets (one pointer each), one hash node per root voxel (next
  /// pointer + cached hash + key + node pointer), every octree node, child array, plane and the
  /// capacity of every point vector, plus 16 bytes of allocator overhead per heap block (glibc:
  /// 8-byte header, 16-byte rounding). Walks the whole map: call it at stats rate, not per point.
  std::size_t bytes() const;
  VoxelMapStats stats() const;

  /// Calls f(key of the root voxel, plane) for every plane leaf.
  void forEachPlane(const std::function<void(const VoxelKey&, const Plane&)>& f) const override;

  /// Calls f(plane, octant path) for every plane leaf of one root voxel (nothing when it does not
  /// exist). The path holds the child index per layer below the root, -1 beyond the leaf's layer.
  void forEachPlaneIn(const VoxelKey& key,
                      const std::function<void(const Plane&, const std::array<std::int8_t, 3>&)>& f) const;

  /// Drops every root voxel whose centre lies outside the axis-aligned cube of half edge
  /// `half_edge_m` around `center` (|c_i - center_i| > half_edge_m on some axis). Returns the count.
  std::size_t removeOutsideBox(const Vec3& center, double half_edge_m);
  /// Drops one root voxel; returns 1 when it existed, else 0.
  std::size_t removeVoxel(const VoxelKey& key);
  void clear();
  /// Binary form of every root voxel's octree (map_file.cpp). load() replaces the contents; it throws
  /// std::runtime_error on malformed or truncated input (the map is then empty).
  void save(std::ostream& os) const;
  void load(std::istream& is);
  /// Calls f(key) for every root voxel.
  void forEachRoot(const std::function<void(const VoxelKey&)>& f) const {
    for (const auto& kv : roots_) f(kv.first);
  }

  const VoxelMapConfig& config() const { return config_; }

 private:
  /// Best accepted plane of one root voxel's octree; updates `out` when better than out.probability.

  VoxelMapConfig config_;
  std::unordered_map<VoxelKey, std::unique_ptr<OctreeNode>, VoxelKeyHash> roots_;
};

}  // namespace livo
