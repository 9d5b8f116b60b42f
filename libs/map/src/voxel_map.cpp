#include "livo/map/voxel_map.hpp"

#include "octree_node.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace livo {
namespace {
constexpr std::size_t kHeapOverhead = 16;  // see VoxelMap::bytes()
}  // namespace

VoxelMap::VoxelMap(VoxelMapConfig config) : config_(std::move(config)) {
  if (!(config_.voxel_size_m > 0.0)) throw std::invalid_argument("VoxelMap: voxel_size_m must be > 0");
  if (config_.max_layer < 0 || config_.max_layer > 6)
    throw std::invalid_argument("VoxelMap: max_layer must be in [0, 6]");
  if (config_.max_points < 3) throw std::invalid_argument("VoxelMap: max_points must be >= 3");
  if (config_.refit_new_points < 1 || config_.refit_new_points > 60000)
    throw std::invalid_argument("VoxelMap: refit_new_points must be in [1, 60000]");
  for (int l = 0; l <= config_.max_layer; ++l) {
    if (config_.initNum(l) < 2)
      throw std::invalid_argument("VoxelMap: layer_init_num[" + std::to_string(l) + "] must be >= 2");
  }
}

VoxelMap::~VoxelMap() = default;
VoxelMap::VoxelMap(VoxelMap&&) noexcept = default;
VoxelMap& VoxelMap::operator=(VoxelMap&&) noexcept = default;

std::size_t VoxelMap::insert(const std::vector<PointWithCov>& points) {
  const double s = config_.voxel_size_m;
  std::size_t taken = 0;
  for (const PointWithCov& pw : points) {
    const Vec3& p = pw.p_world;
    if (!keyablePoint(p, s) || !pw.cov_world.allFinite()) continue;
    const VoxelKey key = keyOf(p);
    auto it = roots_.find(key);
    if (it == roots_.end()) {
      it = roots_.emplace(key, std::make_unique<OctreeNode>(key.center(s), 0)).first;
    }
    it->second->insert(MapPoint(pw), config_);
    ++taken;
  }
  return taken;
}

bool VoxelMap::neighbourKey(const Vec3& p, VoxelKey& out) const {
  return neighbourVoxelKey(p, config_.voxel_size_m, out);
}

void VoxelMap::visitPlanes(const VoxelKey& key, const std::function<void(const Plane&)>& f) const {
  const auto it = roots_.find(key);
  if (it != roots_.end()) it->second->forEachPlane(f);
}

void VoxelMap::forEachPlaneIn(
    const VoxelKey& key, const std::function<void(const Plane&, const std::array<std::int8_t, 3>&)>& f) const {
  const auto it = roots_.find(key);
  if (it == roots_.end()) return;
  it->second->forEachPlaneWithPath([&](const Plane& plane, const std::array<std::int8_t, 3>& path) { f(plane, path); });
}

std::size_t VoxelMap::numPlanes() const {
  std::size_t n = 0;
  for (const auto& kv : roots_) kv.second->forEachPlane([&n](const Plane&) { ++n; });
  return n;
}

VoxelMapStats VoxelMap::stats() const {
  VoxelMapStats s;
  s.root_voxels = roots_.size();
  // Buckets, then per root: the hash node (next pointer, cached hash, key, unique_ptr) + malloc.
  s.bytes = roots_.bucket_count() * sizeof(void*);
  const std::size_t hash_node = sizeof(void*) + sizeof(std::size_t) + sizeof(VoxelKey) +
                                sizeof(std::unique_ptr<OctreeNode>) + kHeapOverhead;
  s.bytes += roots_.size() * hash_node;
  for (const auto& kv : roots_) kv.second->accumulate(s);
  return s;
}

std::size_t VoxelMap::bytes() const { return stats().bytes; }

void VoxelMap::forEachPlane(const std::function<void(const VoxelKey&, const Plane&)>& f) const {
  for (const auto& kv : roots_) {
    const VoxelKey& key = kv.first;
    kv.second->forEachPlane([&](const Plane& plane) { f(key, plane); });
  }
}

std::size_t VoxelMap::removeOutsideBox(const Vec3& center, double half_edge_m) {
  std::size_t removed = 0;
  for (auto it = roots_.begin(); it != roots_.end();) {
    const Vec3 c = it->first.center(config_.voxel_size_m);
    if (((c - center).cwiseAbs().array() > half_edge_m).any()) {
      it = roots_.erase(it);
      ++removed;
    } else {
      ++it;
    }
  }
  return removed;
}

std::size_t VoxelMap::removeVoxel(const VoxelKey& key) { return roots_.erase(key); }

void VoxelMap::clear() { roots_.clear(); }

}  // namespace livo
