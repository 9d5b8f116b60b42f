// One node of a root voxel's plane octree (docs/algorithms.md section 3, "Octree", "Node
// initialisation", "Updates"). Private to libs/map.
//
// States:
//   Pending  collects points until it holds more than layer_init_num[layer], then initialises:
//            plane -> Leaf; not planar below max_layer -> Split; not planar at max_layer -> Leaf.
//   Leaf     appends points and refits all of them after every refit_new_points new ones. A refit
//            that stops being planar splits the node (below max_layer) or drops the plane (at
//            max_layer). At max_points the leaf is frozen: a last refit if points arrived since the
//            previous one, then its points are freed and it never changes again.
//   Split    keeps no points and no plane; routes each point to one of 8 children, created on demand.
// Memory: a Plane is allocated only for plane leaves, the child array only for split nodes.
#pragma once

#include "livo/map/plane.hpp"
#include "livo/map/voxel_map_config.hpp"

#include <array>
#include <istream>
#include <ostream>
#include <cstdint>
#include <memory>
#include <vector>

namespace livo {

struct VoxelMapStats;

class OctreeNode {
 public:
  OctreeNode(const Vec3& center, int layer) : center_(center), layer_(static_cast<std::uint8_t>(layer)) {}

  /// Adds one point that lies in this node's cube (docs/algorithms.md section 3, "Updates").
  void insert(const MapPoint& pt, const VoxelMapConfig& cfg);

  /// Calls f(const Plane&) for every plane leaf below (and including) this node.
  template <class F>
  void forEachPlane(F&& f) const {
    if (plane_) {
      f(static_cast<const Plane&>(*plane_));
    } else if (children_) {
      for (const auto& c : *children_)
        if (c) c->forEachPlane(f);
    }
  }

  /// Calls f(const Plane&, const std::array<std::int8_t, 3>& octants) for every plane leaf below this
  /// node, with the child path from the root (octant per layer below the root, -1 beyond the leaf;
  /// paths deeper than 3 layers keep only the first 3).
  template <class F>
  void forEachPlaneWithPath(F&& f, std::array<std::int8_t, 3> path = {{-1, -1, -1}}, int depth = 0) const {
    if (plane_) {
      f(static_cast<const Plane&>(*plane_), path);
    } else if (children_) {
      for (std::size_t i = 0; i < children_->size(); ++i) {
        if (!(*children_)[i]) continue;
        std::array<std::int8_t, 3> child = path;
        if (depth < 3) child[std::size_t(depth)] = static_cast<std::int8_t>(i);
        (*children_)[i]->forEachPlaneWithPath(f, child, depth + 1);
      }
    }
  }

  /// Binary form of this subtree (map_file.cpp); load() checks every count against `limits` and throws
  /// std::runtime_error on malformed input.
  void save(std::ostream& os) const;
  struct LoadLimits {
    int max_layer = 6;
    std::size_t max_points = 100000;  ///< per node
  };
  static std::unique_ptr<OctreeNode> load(std::istream& is, const LoadLimits& limits, int layer);

  /// Adds this subtree's counts and byte estimate (see VoxelMap::bytes()).
  void accumulate(VoxelMapStats& s) const;

 private:
  enum class State : std::uint8_t { Pending, Leaf, Split };
  using Children = std::array<std::unique_ptr<OctreeNode>, 8>;

  /// Edge of this node's cube: voxel_size / 2^layer.
  double edge(const VoxelMapConfig& cfg) const;
  void initialise(const VoxelMapConfig& cfg);
  /// Fits all points; keeps, replaces or drops the plane; splits a non-planar node below max_layer.
  void refit(const VoxelMapConfig& cfg);
  void split(const VoxelMapConfig& cfg);
  void freeze(const VoxelMapConfig& cfg);
  OctreeNode& childFor(const Vec3& p, const VoxelMapConfig& cfg);

  Vec3 center_;
  std::uint8_t layer_;
  State state_ = State::Pending;
  bool update_enabled_ = true;
  std::uint16_t new_points_ = 0;     ///< points appended since the last fit
  std::vector<MapPoint> points_;     ///< empty for split and frozen nodes
  std::unique_ptr<Plane> plane_;     ///< plane leaves only
  std::unique_ptr<Children> children_;  ///< split nodes only
};

}  // namespace livo
