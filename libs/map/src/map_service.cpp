#include "livo/map/map_service.hpp"

#include "livo/common/timing.hpp"

#include <algorithm>
#include <limits>
#include <tuple>

namespace livo {

MapService::MapService(HybridMapConfig map, VoxelMapConfig lidar, VisualMapConfig visual)
    : map_(std::move(map), std::move(lidar), std::move(visual)) {}

Submap MapService::answer(const MapQuery& q) {
  latest_ = std::max(latest_, q.utime);
  Submap s;
  s.utime = q.utime;
  s.request_id = q.request_id;
  s.voxel_size_m = map_.lidar().voxels().config().voxel_size_m;
  std::vector<VoxelKey> keys = q.keys;
  const auto less = [](const VoxelKey& a, const VoxelKey& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); };
  std::sort(keys.begin(), keys.end(), less);
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  for (const VoxelKey& k : keys) {
    map_.lidar().voxels().forEachPlaneIn(k, [&](const Plane& plane, const std::array<std::int8_t, 3>& path) {
      SubmapPlane sp;
      sp.key = k;
      sp.layer = std::min(plane.layer, 3);
      sp.octant = path;
      for (int l = sp.layer; l < 3; ++l) sp.octant[std::size_t(l)] = -1;
      sp.plane = plane;
      sp.frozen = false;
      s.planes.push_back(sp);
    });
  }
  if (q.want_visual) {
    // Only points in front of the predicted camera can be selected (VisualMap::retrieve needs
    // z >= min_depth_m): the others are not sent.
    const std::size_t first = s.visual_points.size();
    map_.visual().copyPointsIn(q.visual_keys, s.visual_points);
    const Pose T_camera_world = q.T_world_camera.inverse();
    const double min_z = map_.visual().local().config().min_depth_m;
    const double max_z = q.max_visual_depth_m > 0 ? q.max_visual_depth_m : std::numeric_limits<double>::infinity();
    const auto behind = [&](const VisualPoint& p) {
      const double z = (T_camera_world * p.p_world).z();
      return !(z >= min_z && z <= max_z);
    };
    s.visual_points.erase(std::remove_if(s.visual_points.begin() + std::ptrdiff_t(first), s.visual_points.end(), behind),
                          s.visual_points.end());
    ++counters_.visual_queries;
  }
  s.next_visual_point_id = map_.visual().nextId();
  ++counters_.queries;
  return s;
}

MapUpdateReport MapService::apply(const MapUpdate& u) {
  Stopwatch watch;
  ThreadCpuStopwatch cpu;
  latest_ = std::max(latest_, u.utime);
  if (u.utime < latest_update_) ++counters_.stale_updates;
  latest_update_ = std::max(latest_update_, u.utime);
  counters_.points_inserted += map_.lidar().insert(u.points);
  const double insert_cpu_ms = cpu.elapsedMs();
  for (const VisualPoint& p : u.new_visual_points) {
    if (p.obs.empty()) {
      map_.visual().upsert(p);
      ++counters_.visual_removals;
    } else if (map_.visual().upsert(p)) {
      ++counters_.visual_upserts;
    } else {
      ++counters_.visual_rejected;
    }
  }
  for (const auto& ob : u.observations) {
    if (map_.visual().appendObservation(ob.first, ob.second, &map_.lidar().voxels()))
      ++counters_.observations_added;
    else
      ++counters_.observations_unknown;
  }
  const double visual_cpu_ms = cpu.elapsedMs() - insert_cpu_ms;
  MapUpdateReport rep = map_.update(u.T_world_imu.translation());
  const double maintenance_cpu_ms = cpu.elapsedMs() - insert_cpu_ms - visual_cpu_ms;
  counters_.max_insert_cpu_ms = std::max(counters_.max_insert_cpu_ms, insert_cpu_ms);
  counters_.max_visual_cpu_ms = std::max(counters_.max_visual_cpu_ms, visual_cpu_ms);
  counters_.max_maintenance_cpu_ms = std::max(counters_.max_maintenance_cpu_ms, maintenance_cpu_ms);
  if (rep.slid) counters_.last_slide_ms = rep.ms;
  ++counters_.updates;
  counters_.max_update_ms = std::max(counters_.max_update_ms, watch.elapsedMs());
  counters_.max_update_cpu_ms = std::max(counters_.max_update_cpu_ms, cpu.elapsedMs());
  counters_.update_cpu_ms.add(cpu.elapsedMs());
  return rep;
}

MapStats MapService::stats() const {
  const HybridMapStats h = map_.stats();
  MapStats s;
  s.utime = latest_;
  s.local_voxels = std::int64_t(h.local_voxels);
  s.local_planes = std::int64_t(map_.lidar().voxels().numPlanes());
  s.visual_points_local = std::int64_t(h.visual_points_local);
  s.visual_points_longterm = std::int64_t(h.visual_points_longterm);
  s.bytes = std::int64_t(h.bytes);
  s.bytes_cap = std::int64_t(h.cap_bytes);
  s.evicted_visual_points = std::int64_t(h.counters.evicted_longterm_points + h.counters.evicted_local_points);
  s.evicted_voxels = std::int64_t(h.counters.evicted_local_voxels);
  s.slides = std::int64_t(h.counters.slides);
  s.queries_answered = std::int64_t(counters_.queries);
  s.last_slide_ms = float(counters_.last_slide_ms);
  return s;
}

}  // namespace livo
