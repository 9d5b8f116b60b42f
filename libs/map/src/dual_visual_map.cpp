// DualVisualMap: retrieval over both visual maps, per-point dispatch to the holding map, and the
// protocol operations on visual points.
#include "livo/map/dual_visual_map.hpp"

#include "livo/sensors/camera_model.hpp"

#include <algorithm>
#include <limits>
#include <memory>

namespace livo {

DualVisualMap::DualVisualMap(const VisualMapConfig& config) : local_(config), longterm_(config, true) {}

VisualRetrieval DualVisualMap::retrieve(const CameraModel& cam, const Pose& T_world_camera,
                                       const std::vector<Vec3>& scan_points_world,
                                       const std::vector<VoxelKey>* voxel_keys) {
  VisualRetrieval local = local_.retrieve(cam, T_world_camera, scan_points_world, voxel_keys);
  if (longterm_.size() == 0) return local;
  const VisualRetrieval lt = longterm_.retrieve(cam, T_world_camera, scan_points_world, voxel_keys);
  VisualRetrieval got;
  got.grid = local.grid;
  got.stats = local.stats;
  got.stats.visual_voxels += lt.stats.visual_voxels;
  got.stats.searched_points += lt.stats.searched_points;
  got.stats.in_image += lt.stats.in_image;
  got.stats.occluded += lt.stats.occluded;
  if (lt.points.empty()) {
    got.points = std::move(local.points);
    got.pixels = std::move(local.pixels);
    got.occupied = std::move(local.occupied);
    got.stats.selected = got.points.size();
    return got;
  }

  // Per cell the nearer winner (both lists are per-cell winners of the same grid).
  const ImageGrid& grid = got.grid;
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
  for (std::size_t i = 0; i < local.points.size(); ++i) offer(local.points[i], local.pixels[i], false);
  for (std::size_t i = 0; i < lt.points.size(); ++i) offer(lt.points[i], lt.pixels[i], true);

  got.occupied.assign(std::size_t(grid.size()), false);
  for (std::size_t cell = 0; cell < best.size(); ++cell) {
    const Best& b = best[cell];
    if (b.point == nullptr) continue;
    got.occupied[cell] = true;
    got.points.push_back(b.point);
    got.pixels.push_back(b.px);
    got.longterm += b.longterm;
  }
  got.stats.selected = got.points.size();
  return got;
}

int DualVisualMap::addPoints(const Image& gray, const CameraModel& cam, const Pose& T_world_camera, float inv_exposure,
                             Utime t, const std::vector<NewPointCandidate>& candidates,
                             const std::vector<bool>& occupied_cells) {
  return local_.addPoints(gray, cam, T_world_camera, inv_exposure, t, candidates, occupied_cells);
}

bool DualVisualMap::observe(VisualPoint& p, double mean_sq_error, double gate, const Image& gray,
                            const Pose& T_world_camera, const Vec2& px, float inv_exposure, Utime t,
                            const PlaneFinder* planes) {
  VisualMap& holder = holderOf(p);
  holder.reportPhotometricError(p, mean_sq_error, gate);
  if (!holder.addObservation(p, gray, T_world_camera, px, inv_exposure, t)) return false;
  ++added_observations_;
  holder.refine(p, planes);
  return true;
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
}

}  // namespace livo
