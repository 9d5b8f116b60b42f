#include "livo/estimation/remote_map.hpp"

#include "livo/common/timing.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <tuple>

namespace livo {
namespace {

bool keyLess(const VoxelKey& a, const VoxelKey& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); }

void sortUnique(std::vector<VoxelKey>& keys) {
  std::sort(keys.begin(), keys.end(), keyLess);
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

Utime newestObservation(const VisualPoint& p) { return p.obs.empty() ? 0 : p.obs.back().utime; }

}  // namespace

RemoteMap::PointSignature::PointSignature(const VisualPoint& p)
    : n_obs(p.obs.size()), newest(newestObservation(p)), reference(p.reference), bad_updates(p.bad_updates),
      converged(p.converged), normal(p.normal), p_world(p.p_world) {}

bool RemoteMap::PointSignature::same(const VisualPoint& p) const {
  return n_obs == p.obs.size() && newest == newestObservation(p) && reference == p.reference &&
         bad_updates == p.bad_updates && converged == p.converged && normal == p.normal;
}

RemoteMap::RemoteMap(const PipelineConfig& cfg, MapClient& client)
    : voxel_size_m_(cfg.lio.map.voxel_size_m),
      visual_voxel_size_m_(cfg.visual_map.voxel_size_m),
      T_imu_camera_(cfg.camera.T_imu_camera),
      client_(client),
      planes_(cfg.lio.map.voxel_size_m, cfg.lio.map.sigma_num),
      cache_(cfg.visual_map) {}

MapQuery RemoteMap::queryAt(const Frame& frame, const NavState& x) const {
  MapQuery q;
  q.utime = frame.utime;
  q.T_world_imu = x.pose();
  q.T_world_camera = q.T_world_imu * T_imu_camera_;
  return q;
}

bool RemoteMap::ask(MapQuery& q, Submap& out) {
  q.request_id = ++request_id_;
  ++link_.queries;
  Stopwatch wait;
  const bool ok = client_.request(q, out) && out.request_id == q.request_id;
  link_.wait_ms += wait.elapsedMs();
  if (!ok) {
    ++link_.timeouts;
    ++timeouts_;
    link_.map_timeout = true;
  }
  return ok;
}

const PlaneFinder& RemoteMap::planesFor(const Frame& frame, const LioFrameResult& lio) {
  estimating_ = true;
  visual_ran_ = false;
  registered_.clear();
  link_ = MapLinkReport{};
  // Each predicted point's root voxel and the neighbour the association may try (the update moves
  // points by far less than the quarter voxel that rule covers).
  const double s = voxel_size_m_;
  MapQuery q = queryAt(frame, lio.state);
  for (const Vec3& p : scanInWorld(lio.state, lio.points)) {
    if (!keyablePoint(p, s)) continue;
    q.keys.push_back(VoxelKey::fromPoint(p, s));
    VoxelKey near;
    if (neighbourVoxelKey(p, s, near)) q.keys.push_back(near);
  }
  sortUnique(q.keys);
  link_.query_keys = q.keys.size();
  Submap sub;
  if (ask(q, sub)) {
    if (std::abs(sub.voxel_size_m - s) > 1e-9 * s) ++voxel_size_mismatches_;
    planes_.reset(sub.voxel_size_m);
    for (const SubmapPlane& sp : sub.planes) planes_.add(sp.key, sp.plane);
    link_.submap_planes = sub.planes.size();
    cache_.local().raiseNextId(sub.next_visual_point_id);
  }  // else: the planes of the last answer
  return planes_;
}

void RemoteMap::insertScan(std::vector<PointWithCov> points) { registered_ = std::move(points); }

FrameVisualMap RemoteMap::visualMap(const Frame& frame, const NavState& x, const std::vector<VoxelKey>* frustum_keys) {
  // The visual points of the visual voxels the registered scan touches, or of the camera frustum
  // when the LiDAR failed (both server maps). Not after this frame's first query went unanswered:
  // a map server that does not answer would only cost a second wait.
  if (link_.map_timeout) return {};
  MapQuery q = queryAt(frame, x);
  q.want_visual = true;
  if (frustum_keys != nullptr) {
    q.visual_keys = *frustum_keys;
  } else {
    for (const PointWithCov& pw : registered_)
      if (keyablePoint(pw.p_world, visual_voxel_size_m_))
        q.visual_keys.push_back(VoxelKey::fromPoint(pw.p_world, visual_voxel_size_m_));
  }
  sortUnique(q.visual_keys);
  link_.visual_keys = q.visual_keys.size();
  Submap sub;
  if (!ask(q, sub)) return {};
  link_.submap_visual_points = sub.visual_points.size();

  // A per-frame copy of the server's points, with their state before the step.
  cache_.clear();
  VisualMap& cached = cache_.local();
  cached.raiseNextId(sub.next_visual_point_id);
  before_.clear();
  before_.reserve(sub.visual_points.size());
  for (VisualPoint& p : sub.visual_points) {
    const PointSignature sig(p);
    const std::int64_t id = p.id;
    if (cached.insert(std::make_unique<VisualPoint>(std::move(p)))) before_.emplace(id, sig);
  }
  first_new_id_ = cached.nextId();
  visual_ran_ = true;
  return {&cache_, &planes_};
}

void RemoteMap::collectVisualChanges(std::vector<VisualPoint>& out) const {
  const VisualMap& cached = cache_.local();
  cached.forEach([&](const VisualPoint& p) {
    const auto it = before_.find(p.id);
    if (p.id >= first_new_id_ || (it != before_.end() && !it->second.same(p))) out.push_back(p);
  });
  for (const auto& kv : before_) {
    if (cached.find(kv.first) != nullptr) continue;
    VisualPoint gone;
    gone.id = kv.first;
    gone.p_world = kv.second.p_world;
    out.push_back(std::move(gone));
  }
}

MapFrameReport RemoteMap::finishFrame(const Frame& frame, const NavState& x) {
  MapFrameReport report;
  if (!estimating_) return report;  // a frame inside the initialisation window: nothing for the map
  estimating_ = false;
  MapUpdate update;
  update.utime = frame.utime;
  update.request_id = request_id_;
  update.T_world_imu = x.pose();
  // The registered points stay at the LiDAR posterior: the single process inserts the scan before the
  // visual update too.
  update.points = std::move(registered_);
  registered_.clear();
  if (visual_ran_) collectVisualChanges(update.new_visual_points);
  visual_ran_ = false;
  link_.update_points = update.points.size();
  link_.update_visual_points = update.new_visual_points.size();
  client_.send(update);
  report.link = link_;
  link_ = MapLinkReport{};
  return report;
}

}  // namespace livo
