#include "octree_node.hpp"

#include "livo/map/voxel_map.hpp"

#include <cmath>

namespace livo {
namespace {
constexpr std::size_t kHeapOverhead = 16;  // glibc malloc: 8-byte header, 16-byte rounding
}

double OctreeNode::edge(const VoxelMapConfig& cfg) const { return std::ldexp(cfg.voxel_size_m, -layer_); }

void OctreeNode::insert(const MapPoint& pt, const VoxelMapConfig& cfg) {
  switch (state_) {
    case State::Pending:
      points_.push_back(pt);
      if (static_cast<int>(points_.size()) > cfg.initNum(layer_)) initialise(cfg);
      return;
    case State::Split:
      childFor(pt.p_world, cfg).insert(pt, cfg);
      return;
    case State::Leaf:
      if (!update_enabled_) return;  // frozen: the plane (or non-plane) is final
      points_.push_back(pt);
      ++new_points_;
      if (new_points_ >= cfg.refit_new_points) refit(cfg);
      if (state_ == State::Leaf && static_cast<int>(points_.size()) >= cfg.max_points) freeze(cfg);
      return;
  }
}

void OctreeNode::initialise(const VoxelMapConfig& cfg) {
  state_ = State::Leaf;
  refit(cfg);
  if (state_ == State::Leaf && static_cast<int>(points_.size()) >= cfg.max_points) freeze(cfg);
}

void OctreeNode::refit(const VoxelMapConfig& cfg) {
  new_points_ = 0;
  Plane fit;
  if (fitPlane(points_, cfg.min_eigen_value, fit)) {
    fit.layer = layer_;
    if (plane_) {
      *plane_ = fit;
    } else {
      plane_ = std::make_unique<Plane>(fit);
    }
    return;
  }
  plane_.reset();
  if (layer_ < cfg.max_layer) split(cfg);  // not planar: hand the points to 8 children
  // else: a non-plane leaf at max_layer keeps collecting (it may become planar on a later refit).
}

void OctreeNode::split(const VoxelMapConfig& cfg) {
  state_ = State::Split;
  plane_.reset();
  std::vector<MapPoint> pts;
  pts.swap(points_);  // frees this node's buffer: a split node keeps no points (section 8)
  children_ = std::make_unique<Children>();
  // Distribute first, then initialise each child on all its points at once (one fit, not a refit
  // every few points).
  for (const MapPoint& pt : pts) childFor(pt.p_world, cfg).points_.push_back(pt);
  for (auto& c : *children_) {
    if (c && static_cast<int>(c->points_.size()) > cfg.initNum(c->layer_)) c->initialise(cfg);
  }
}

void OctreeNode::freeze(const VoxelMapConfig& cfg) {
  if (new_points_ > 0) {
    refit(cfg);  // use every point once before they are freed
    if (state_ != State::Leaf) return;  // became non-planar and split: the children carry on
  }
  update_enabled_ = false;
  new_points_ = 0;
  std::vector<MapPoint>().swap(points_);
}

OctreeNode& OctreeNode::childFor(const Vec3& p, const VoxelMapConfig& cfg) {
  // Child index 4x + 2y + z; the upper half includes the centre, like floor() for the root keys.
  const int ix = p.x() >= center_.x() ? 1 : 0;
  const int iy = p.y() >= center_.y() ? 1 : 0;
  const int iz = p.z() >= center_.z() ? 1 : 0;
  auto& slot = (*children_)[4 * ix + 2 * iy + iz];
  if (!slot) {
    const double quarter = 0.25 * edge(cfg);
    const Vec3 c = center_ + quarter * Vec3(2 * ix - 1, 2 * iy - 1, 2 * iz - 1);
    slot = std::make_unique<OctreeNode>(c, layer_ + 1);
  }
  return *slot;
}

void OctreeNode::accumulate(VoxelMapStats& s) const {
  ++s.nodes;
  s.bytes += sizeof(OctreeNode) + kHeapOverhead;
  if (points_.capacity() > 0) s.bytes += points_.capacity() * sizeof(MapPoint) + kHeapOverhead;
  s.stored_points += points_.size();
  if (plane_) {
    ++s.planes;
    s.bytes += sizeof(Plane) + kHeapOverhead;
  }
  if (state_ == State::Leaf && !update_enabled_) ++s.frozen_leaves;
  if (children_) {
    s.bytes += sizeof(Children) + kHeapOverhead;
    for (const auto& c : *children_)
      if (c) c->accumulate(s);
  }
}

}  // namespace livo
