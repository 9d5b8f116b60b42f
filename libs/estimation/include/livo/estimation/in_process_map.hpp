// The map access of the single process (livo-run, the tests): the HybridMap itself.
//   step 2: its local LiDAR plane map; step 3b: insertion (the tile index for slides included);
//   step 6: both visual maps (local and long-term), normals refined against the LiDAR map, which
//   already holds this frame's scan; step 7: HybridMap::update at the frame's final position
//   (slides when due, their work spread over frames, and the memory cap).
#pragma once

#include "livo/estimation/map_access.hpp"
#include "livo/map/hybrid_map.hpp"

namespace livo {

class InProcessMap final : public MapAccess {
 public:
  /// `map` is not owned and must outlive this object.
  explicit InProcessMap(HybridMap& map) : map_(map) {}

  const PlaneFinder& planesFor(const Frame&, const LioFrameResult&) override { return map_.lidar().voxels(); }
  void insertScan(std::vector<PointWithCov> points) override { map_.lidar().insert(points); }
  bool holdsAround(const LioFrameResult& lio, int min_points) override {
    const VoxelMap& m = map_.lidar().voxels();
    int on_planes = 0;
    for (const Vec3& p : scanInWorld(lio.state, lio.points)) {
      if (!keyablePoint(p, m.config().voxel_size_m)) continue;
      bool plane = false;
      m.visitPlanes(m.keyOf(p), [&plane](const Plane&) { plane = true; });
      if (plane && ++on_planes >= min_points) return true;
    }
    return false;
  }
  FrameVisualMap visualMap(const Frame&, const NavState&, const std::vector<VoxelKey>*) override {
    return {&map_.visual(), &map_.lidar().voxels()};
  }
  MapFrameReport finishFrame(const Frame&, const NavState& x) override { return {map_.update(x.p_world_imu), {}}; }

 private:
  HybridMap& map_;
};

}  // namespace livo
