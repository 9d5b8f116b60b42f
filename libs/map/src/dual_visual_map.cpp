// DualVisualMap: retrieval over both visual maps, per-point dispatch to the holding map, and the
// protocol operations on visual points.
#include "livo/map/dual_visual_map.hpp"

#include "livo/sensors/camera_model.hpp"

#include <algorithm>
#include <limits>
#include <memory>

namespace livo {

DualVisualMap::DualVisualMap(const VisualMapConfig& config) : local_(config), longterm_(config, true) {}

std::vector<VisualPoint*> DualVisualMap::pointsInView(const CameraModel& cam, const Pose& T_world_camera,
                                                      const std::vector<Vec3>& scan_points_world,
                                                      std::vector<Vec2>* pixels,
                                                      const std::vector<VoxelKey>* voxel_keys) {
  std::vector<Vec2> px_local;
  std::vector<VisualPoint*> local = local_.pointsInView(cam, T_world_camera, scan_points_world, &px_local, voxel_keys);
  retrieval_ = local_.lastRetrieval();
  occupied_ = local_.occupiedCells();
  retrieved_longterm_ = 0;
  if (longterm_.size() == 0) {
    if (pixels) *pixels = std::move(px_local);
    return local;
  }
  std::vector<Vec2> px_lt;
  std::vector<VisualPoint*> lt = longterm_.pointsInView(cam, T_world_camera, scan_points_world, &px_lt, voxel_keys);
  const VisualRetrievalStats& rs = longterm_.lastRetrieval();
  retrieval_.visual_voxels += rs.visual_voxels;
  retrieval_.searched_points += rs.searched_points;
  retrieval_.in_image += rs.in_image;
  retrieval_.occluded += rs.occluded;
  if (lt.empty()) {
    if (pixels) *pixels = std::move(px_local);
    return local;
  }

  // Per cell the nearer winner (both lists are per-cell winners of the same grid).
  const ImageGrid grid = gridFor(cam);
  const Pose T_camera_world = T_world_camera.inverse();
  struct Best {
    VisualPoint* point = nullptr;
    Vec2 px = Vec2::Zero();
    double z = std::numeric_limits<double>::infinity();
    bool longterm = false;
  };
  std::vector<Best> best(std::size_t(grid.size()));
  auto offer = [&](VisualPoint* p, const Vec2& px, bool longterm) {
    const int cell = grid.cellOf(px);
    if (cell < 0) return;
    const double z = (T_camera_world * p->p_world).z();
    Best& b = best[std::size_t(cell)];
    if (winsCell(*p, z, b.point, b.z, local_.config().occlusion_depth_m)) b = {p, px, z, longterm};
  };
  for (std::size_t i = 0; i < local.size(); ++i) offer(local[i], px_local[i], false);
  for (std::size_t i = 0; i < lt.size(); ++i) offer(lt[i], px_lt[i], true);

  std::vector<VisualPoint*> out;
  if (pixels) pixels->clear();
  occupied_.assign(std::size_t(grid.size()), false);
  for (std::size_t cell = 0; cell < best.size(); ++cell) {
    const Best& b = best[cell];
    if (b.point == nullptr) continue;
    occupied_[cell] = true;
    out.push_back(b.point);
    if (pixels) pixels->push_back(b.px);
    retrieved_longterm_ += b.longterm;
  }
  retrieval_.selected = out.size();
  return out;
}

int DualVisualMap::addPoints(const Image& gray, const CameraModel& cam, const Pose& T_world_camera, float inv_exposure,
                             Utime t, const std::vector<NewPointCandidate>& candidates,
                             const std::vector<bool>& occupied_cells) {
  return local_.addPoints(gray, cam, T_world_camera, inv_exposure, t, candidates, occupied_cells);
}

bool DualVisualMap::addObservation(VisualPoint& p, const Image& gray, const Pose& T_world_camera, const Vec2& px,
                                   float inv_exposure, Utime t) {
  const bool added = holderOf(p).addObservation(p, gray, T_world_camera, px, inv_exposure, t);
  added_observations_ += added;
  return added;
}

void DualVisualMap::refine(VisualPoint& p, const PlaneFinder* lidar) { holderOf(p).refine(p, lidar); }

void DualVisualMap::reportPhotometricError(VisualPoint& p, double mean_sq_error, double gate) {
  holderOf(p).reportPhotometricError(p, mean_sq_error, gate);
}

std::size_t DualVisualMap::removeBadPoints() { return local_.removeBadPoints() + longterm_.removeBadPoints(); }

std::size_t DualVisualMap::copyPointsIn(const std::vector<VoxelKey>& visual_keys, std::vector<VisualPoint>& out) const {
  std::vector<VoxelKey> keys = visual_keys;
  std::sort(keys.begin(), keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
    return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
  });
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  const std::size_t before = out.size();
  const auto copy = [&out](const VisualPoint& p) { out.push_back(p); };
  for (const VoxelKey& k : keys) {
    local_.forEachInVoxel(k, copy);
    longterm_.forEachInVoxel(k, copy);
  }
  return out.size() - before;
}

bool DualVisualMap::upsert(VisualPoint p) {
  // A rejected point leaves the one it would replace in place.
  if (!p.obs.empty() && (!p.p_world.allFinite() || p.reference < -1 || p.reference >= int(p.obs.size()))) return false;
  VisualMap* owner = &local_;
  std::size_t old_obs = 0;
  bool returned = false;  // the point came back from the long-term map to the local one
  if (auto old = local_.extract(p.id)) {
    old_obs = old->obs.size();
    returned = old->from_longterm;
  } else if (auto old_lt = longterm_.extract(p.id)) {
    owner = &longterm_;  // which marks it on insertion
    old_obs = old_lt->obs.size();
  }
  if (p.obs.empty()) return true;  // a removal
  // The sender's copy may predate the point's move to the long-term map.
  p.from_longterm = p.from_longterm || returned;
  if (p.obs.size() > old_obs) added_observations_ += p.obs.size() - old_obs;
  return owner->insert(std::make_unique<VisualPoint>(std::move(p)));
}

bool DualVisualMap::appendObservation(std::int64_t id, const VisualObservation& obs, const PlaneFinder* lidar) {
  VisualMap* owner = &local_;
  VisualPoint* p = local_.find(id);
  if (p == nullptr) {
    owner = &longterm_;
    p = longterm_.find(id);
  }
  if (p == nullptr || p->converged) return false;
  p->obs.push_back(obs);
  ++p->views;
  p->last_seen = std::max(p->last_seen, obs.utime);
  ++added_observations_;
  owner->refine(*p, lidar);
  return true;
}

void DualVisualMap::clear() {
  local_.clear();
  longterm_.clear();
  occupied_.clear();
}

}  // namespace livo
