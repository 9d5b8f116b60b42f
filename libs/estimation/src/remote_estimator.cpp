#include "livo/estimation/remote_estimator.hpp"

#include "livo/common/timing.hpp"
#include "livo/estimation/visual_step.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <unordered_map>

namespace livo {
namespace {

bool keyLess(const VoxelKey& a, const VoxelKey& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); }

void sortUnique(std::vector<VoxelKey>& keys) {
  std::sort(keys.begin(), keys.end(), keyLess);
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

/// What identifies a change of a visual point by the visual step.
struct PointSignature {
  std::size_t n_obs = 0;
  Utime newest = 0;
  int reference = -1;
  int bad_updates = 0;
  bool converged = false;
  Vec3 normal = Vec3::Zero();
  Vec3 p_world = Vec3::Zero();
  explicit PointSignature(const VisualPoint& p)
      : n_obs(p.obs.size()), newest(p.obs.empty() ? 0 : p.obs.back().utime), reference(p.reference),
        bad_updates(p.bad_updates), converged(p.converged), normal(p.normal), p_world(p.p_world) {}
  bool same(const VisualPoint& p) const {
    return n_obs == p.obs.size() && newest == (p.obs.empty() ? 0 : p.obs.back().utime) && reference == p.reference &&
           bad_updates == p.bad_updates && converged == p.converged && normal == p.normal;
  }
};

}  // namespace

RemoteEstimator::RemoteEstimator(PipelineConfig cfg)
    : cfg_(std::move(cfg)),
      lio_(cfg_.lio, LioOdometry::RemoteMapTag{}),
      selector_(cfg_.selector, parseVisualMode(cfg_.visual_mode)),
      planes_(cfg_.lio.map.voxel_size_m, cfg_.lio.map.sigma_num),
      cache_(cfg_.visual_map) {
  if (cfg_.camera.enabled) camera_ = CameraModel::create(cfg_.camera);
}

bool RemoteEstimator::query(MapQuery& q, Submap& out, RemoteFrameResult& r, MapClient& client) {
  q.request_id = ++request_id_;
  ++r.queries;
  Stopwatch wait;
  const bool ok = client.request(q, out) && out.request_id == q.request_id;
  r.wait_ms += wait.elapsedMs();
  if (!ok) {
    ++r.timeouts;
    ++timeouts_;
    r.map_timeout = true;
  }
  return ok;
}

RemoteFrameResult RemoteEstimator::process(const Frame& frame, MapClient& client) {
  Stopwatch watch;
  RemoteFrameResult r;
  FrameResult& f = r.frame;
  ++frames_;
  // 1-2. Initialisation, propagation, undistortion (nothing to do before the IMU is initialised).
  if (!lio_.predict(frame, f.lio)) {
    f.total_ms = watch.elapsedMs();
    return r;
  }

  // The planes around the predicted scan: each point's root voxel and the neighbour the association
  // may try (the update moves points by far less than the quarter voxel that rule covers).
  const double s = cfg_.lio.map.voxel_size_m;
  MapQuery q;
  q.utime = frame.utime;
  q.T_world_imu = f.lio.state.pose();
  q.T_world_camera = q.T_world_imu * cfg_.camera.T_imu_camera;
  for (const Vec3& p : scanInWorld(f.lio.state, f.lio.points)) {
    if (!keyablePoint(p, s)) continue;
    q.keys.push_back(VoxelKey::fromPoint(p, s));
    VoxelKey near;
    if (neighbourVoxelKey(p, s, near)) q.keys.push_back(near);
  }
  sortUnique(q.keys);
  r.query_keys = q.keys.size();
  Submap sub;
  if (query(q, sub, r, client)) {
    if (std::abs(sub.voxel_size_m - s) > 1e-9 * s) ++voxel_size_mismatches_;
    planes_.reset(sub.voxel_size_m);
    for (const SubmapPlane& sp : sub.planes) planes_.add(sp.key, sp.plane);
    r.submap_planes = sub.planes.size();
    cache_.raiseNextId(sub.next_visual_point_id);
  }  // else: the planes of the last answer

  // 2b. Iterated LiDAR update; the registered points go to the map server.
  lio_.update(f.lio, planes_);
  f.lio.lio_ms = std::max(0.0, f.lio.lio_ms - r.wait_ms);
  MapUpdate update;
  update.utime = frame.utime;
  update.request_id = request_id_;
  r.registered = lio_.worldPoints(f.lio.points);
  lio_.markInserted(f.lio);

  // 3. Degeneracy; 4-6. frame selection, photometric update, visual map changes.
  f.degenerate = selector_.degenerate(f.lio.n_matched > 0, f.lio.sigma_min);
  Image scratch;
  const Image* gray = nullptr;
  if (camera_ && frame.has_image) {
    gray = processingImage(frame.image, cfg_.camera, *camera_, scratch);
    if (gray == nullptr) ++images_wrong_size_;  // not the calibrated camera: never read it with this model
  }
  if (gray != nullptr && f.lio.lio_ok && selector_.select(f.lio.state, f.lio.sigma_min, f.degenerate))
    visualStep(frame, *gray, r, client, update);

  // 7. The map changes, with the final pose.
  update.T_world_imu = f.lio.state.pose();
  update.points = r.registered;
  r.update_points = update.points.size();
  r.update_visual_points = update.new_visual_points.size();
  client.send(update);
  f.total_ms = watch.elapsedMs();
  return r;
}

void RemoteEstimator::visualStep(const Frame& frame, const Image& gray, RemoteFrameResult& r, MapClient& client,
                                 MapUpdate& update) {
  FrameResult& f = r.frame;
  Stopwatch watch;
  const CameraModel& cam = *camera_;
  // The visual points of the visual voxels the registered scan touches (both server maps).
  const double vs = cfg_.visual_map.voxel_size_m;
  MapQuery q;
  q.utime = frame.utime;
  q.T_world_imu = f.lio.state.pose();
  q.T_world_camera = q.T_world_imu * cfg_.camera.T_imu_camera;
  q.want_visual = true;
  for (const PointWithCov& pw : r.registered)
    if (keyablePoint(pw.p_world, vs)) q.visual_keys.push_back(VoxelKey::fromPoint(pw.p_world, vs));
  sortUnique(q.visual_keys);
  r.visual_keys = q.visual_keys.size();
  Submap sub;
  const double wait_before = r.wait_ms;
  if (!query(q, sub, r, client)) return;  // no visual update without the map's points
  r.submap_visual_points = sub.visual_points.size();

  // A per-frame copy of the server's points, with their state before the step.
  cache_.clear();
  cache_.raiseNextId(sub.next_visual_point_id);
  std::unordered_map<std::int64_t, PointSignature> before;
  before.reserve(sub.visual_points.size());
  for (VisualPoint& p : sub.visual_points) {
    const PointSignature sig(p);
    const std::int64_t id = p.id;
    if (cache_.insert(std::make_unique<VisualPoint>(std::move(p)))) before.emplace(id, sig);
  }
  const std::int64_t first_new_id = cache_.nextId();

  NavState x = f.lio.state;
  StateCov P = f.lio.P;
  SingleVisualOps ops(cache_, &planes_);
  const VisualStepResult step =
      runVisualStep(ops, x, P, gray, cam, cfg_.camera.T_imu_camera, cfg_.vio, frame.utime, f.lio);
  if (step.update.points_used > 0) lio_.setState(x, P);
  selector_.markUsed(x);

  // Created and changed points in full; removed ones as points without observations.
  cache_.forEach([&](const VisualPoint& p) {
    const auto it = before.find(p.id);
    if (p.id >= first_new_id || (it != before.end() && !it->second.same(p))) update.new_visual_points.push_back(p);
  });
  for (const auto& kv : before) {
    if (cache_.find(kv.first) != nullptr) continue;
    VisualPoint gone;
    gone.id = kv.first;
    gone.p_world = kv.second.p_world;
    update.new_visual_points.push_back(std::move(gone));
  }
  // r.registered stays at the LiDAR posterior: the single process inserts the scan before the visual
  // update too.

  f.visual_used = true;
  f.n_visual_points = step.update.points_used;
  f.n_new_visual_points = step.n_new_points;
  f.vio_rms_before = step.update.rms_before;
  f.vio_rms_after = step.update.rms_after;
  f.lio.state = x;
  f.lio.P = P;
  f.vio_ms = std::max(0.0, watch.elapsedMs() - (r.wait_ms - wait_before));
}

}  // namespace livo
