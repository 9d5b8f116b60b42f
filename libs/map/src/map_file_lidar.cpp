// Binary form of the LiDAR map in map files (map_file.hpp): the save/load members of OctreeNode and
// VoxelMap (per root: its key, then its octree depth first, each node with its points and plane).
#include "livo/map/voxel_map.hpp"

#include "map_file_codec.hpp"
#include "octree_node.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace livo {

using namespace map_codec;

namespace {

constexpr std::uint64_t kMaxRoots = 100'000'000;

void putPlane(std::ostream& os, const Plane& p) {
  putVec(os, p.center);
  putVec(os, p.normal);
  put(os, p.d);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) put(os, p.cov_nq(r, c));
  put(os, p.radius); put(os, p.eig_min); put(os, p.eig_mid); put(os, p.eig_max);
  put(os, std::int32_t(p.num_points)); put(os, std::int32_t(p.layer)); put(os, std::uint8_t(p.is_plane));
}

Plane getPlane(std::istream& is) {
  Plane p;
  p.center = getVec3(is, "plane centre");
  p.normal = getVec3(is, "plane normal");
  p.d = getFinite(is, "plane offset");
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) p.cov_nq(r, c) = getFinite(is, "plane covariance");
  p.radius = getFinite(is, "plane radius");
  p.eig_min = getFinite(is, "plane eigenvalue");
  p.eig_mid = getFinite(is, "plane eigenvalue");
  p.eig_max = getFinite(is, "plane eigenvalue");
  p.num_points = get<std::int32_t>(is, "plane point count");
  p.layer = get<std::int32_t>(is, "plane layer");
  p.is_plane = get<std::uint8_t>(is, "plane flag") != 0;
  return p;
}

}  // namespace

// ---- OctreeNode ----
void OctreeNode::save(std::ostream& os) const {
  putVec(os, center_);
  put(os, layer_); put(os, std::uint8_t(state_)); put(os, std::uint8_t(update_enabled_)); put(os, new_points_);
  put(os, std::uint32_t(points_.size()));
  for (const MapPoint& p : points_) {
    putVec(os, p.p_world);
    put(os, p.cov_upper);
  }
  put(os, std::uint8_t(plane_ != nullptr));
  if (plane_) putPlane(os, *plane_);
  std::uint8_t mask = 0;
  if (children_)
    for (std::size_t i = 0; i < 8; ++i)
      if ((*children_)[i]) mask |= std::uint8_t(1u << i);
  put(os, std::uint8_t(children_ != nullptr)); put(os, mask);
  if (children_)
    for (const auto& c : *children_)
      if (c) c->save(os);
}

std::unique_ptr<OctreeNode> OctreeNode::load(std::istream& is, const LoadLimits& limits, int layer) {
  const Vec3 center = getVec3(is, "node centre");
  const auto stored_layer = get<std::uint8_t>(is, "node layer");
  if (int(stored_layer) != layer) throw std::runtime_error("node layer " + std::to_string(stored_layer) + " at depth " + std::to_string(layer));
  auto node = std::make_unique<OctreeNode>(center, layer);
  const auto state = get<std::uint8_t>(is, "node state");
  if (state > std::uint8_t(State::Split)) throw std::runtime_error("node state " + std::to_string(state));
  node->state_ = State(state);
  node->update_enabled_ = get<std::uint8_t>(is, "node update flag") != 0;
  node->new_points_ = get<std::uint16_t>(is, "node new points");
  const auto n = get<std::uint32_t>(is, "node point count");
  if (n > limits.max_points) throw std::runtime_error("node point count " + std::to_string(n) + " over the limit");
  node->points_.resize(n);
  for (MapPoint& p : node->points_) {
    p.p_world = getVec3(is, "map point");
    p.cov_upper = get<std::array<float, 6>>(is, "map point covariance");
  }
  if (get<std::uint8_t>(is, "plane flag")) node->plane_ = std::make_unique<Plane>(getPlane(is));
  const bool has_children = get<std::uint8_t>(is, "children flag") != 0;
  const auto mask = get<std::uint8_t>(is, "children mask");
  if (has_children) {
    if (layer >= limits.max_layer) throw std::runtime_error("octree deeper than max_layer");
    node->children_ = std::make_unique<Children>();
    for (std::size_t i = 0; i < 8; ++i)
      if (mask & (1u << i)) (*node->children_)[i] = load(is, limits, layer + 1);
  }
  return node;
}

// ---- VoxelMap ----
void VoxelMap::save(std::ostream& os) const {
  put(os, std::uint64_t(roots_.size()));
  for (const auto& kv : roots_) {
    put(os, kv.first.x); put(os, kv.first.y); put(os, kv.first.z);
    kv.second->save(os);
  }
}

void VoxelMap::load(std::istream& is) {
  clear();
  try {
    const auto n = get<std::uint64_t>(is, "root voxel count");
    if (n > kMaxRoots) throw std::runtime_error("root voxel count " + std::to_string(n) + " over the limit");
    OctreeNode::LoadLimits lim;
    lim.max_layer = config_.max_layer;
    lim.max_points = std::size_t(std::max(config_.max_points, 1)) * 2 + 1024;
    for (std::uint64_t i = 0; i < n; ++i) {
      VoxelKey k;
      k.x = get<std::int64_t>(is, "voxel key");
      k.y = get<std::int64_t>(is, "voxel key");
      k.z = get<std::int64_t>(is, "voxel key");
      if (!roots_.emplace(k, OctreeNode::load(is, lim, 0)).second) throw std::runtime_error("duplicate root voxel");
    }
  } catch (...) {
    clear();
    throw;
  }
}

}  // namespace livo
