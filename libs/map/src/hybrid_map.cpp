// HybridMap: construction, insertion, retrieval over both visual maps, per-point dispatch, accounting.
// Sliding and the memory cap are in hybrid_map_update.cpp.
#include "livo/map/hybrid_map.hpp"

#include "livo/sensors/camera_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace livo {

namespace {
int tileVoxels(const HybridMapConfig& c, const VoxelMapConfig& v) {
  return std::max(1, static_cast<int>(std::lround(c.tile_edge_m / v.voxel_size_m)));
}
}  // namespace

HybridMap::HybridMap(HybridMapConfig config, VoxelMapConfig lidar_config, VisualMapConfig visual_config)
    : cfg_((config.validate(), std::move(config))),
      lidar_(lidar_config),
      local_visual_(visual_config),
      longterm_visual_(visual_config),
      tiles_(lidar_config.voxel_size_m, tileVoxels(cfg_, lidar_config)),
      // Defaults until the first exact count (1300 B per root voxel incl. index: the simulated street
      // with a spinning 32-ring LiDAR, 0.5 m voxels).
      bytes_per_root_(1300.0),
      bytes_per_local_point_(double(sizeof(VisualPoint) + 4 * sizeof(VisualObservation) + 128)),
      bytes_per_longterm_point_(double(sizeof(VisualPoint) + sizeof(VisualObservation) + 128)) {}

std::size_t HybridMap::insertLidar(const std::vector<PointWithCov>& points) {
  if (cfg_.mode != MapMode::Hybrid) return lidar_.insert(points);
  // One point at a time, in the same order, so that a new root voxel is seen (the root count grows)
  // and only new roots go into the tile index: indexing every point cost ~0.4 us per point.
  std::size_t taken = 0;
  index_scratch_.resize(1);
  for (const PointWithCov& pw : points) {
    index_scratch_[0] = pw;
    const std::size_t roots_before = lidar_.numRootVoxels();
    taken += lidar_.insert(index_scratch_);
    if (lidar_.numRootVoxels() != roots_before) tiles_.add(lidar_.keyOf(pw.p_world));
  }
  points_since_recount_ += taken;
  return taken;
}

std::vector<VisualPoint*> HybridMap::pointsInView(const CameraModel& cam, const Pose& T_world_camera,
                                                  const std::vector<Vec3>& scan_points_world,
                                                  std::vector<Vec2>* pixels) {
  std::vector<Vec2> px_local;
  std::vector<VisualPoint*> local = local_visual_.pointsInView(cam, T_world_camera, scan_points_world, &px_local);
  retrieval_ = local_visual_.lastRetrieval();
  occupied_ = local_visual_.occupiedCells();
  retrieved_longterm_ = 0;
  if (longterm_visual_.size() == 0) {
    if (pixels) *pixels = std::move(px_local);
    return local;
  }
  std::vector<Vec2> px_lt;
  std::vector<VisualPoint*> lt = longterm_visual_.pointsInView(cam, T_world_camera, scan_points_world, &px_lt);
  const VisualRetrievalStats& rs = longterm_visual_.lastRetrieval();
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
    if (b.point == nullptr || z < b.z || (z == b.z && p->id < b.point->id)) b = {p, px, z, longterm};
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

int HybridMap::addPoints(const Image& gray, const CameraModel& cam, const Pose& T_world_camera, float inv_exposure,
                         Utime t, const std::vector<NewPointCandidate>& candidates,
                         const std::vector<bool>& occupied_cells) {
  return local_visual_.addPoints(gray, cam, T_world_camera, inv_exposure, t, candidates, occupied_cells);
}

bool HybridMap::addObservation(VisualPoint& p, const Image& gray, const Pose& T_world_camera, const Vec2& px,
                               float inv_exposure, Utime t) {
  VisualMap& owner = isLongterm(p) ? longterm_visual_ : local_visual_;
  const bool added = owner.addObservation(p, gray, T_world_camera, px, inv_exposure, t);
  obs_since_recount_ += added;
  return added;
}

void HybridMap::refine(VisualPoint& p) {
  VisualMap& owner = isLongterm(p) ? longterm_visual_ : local_visual_;
  owner.refine(p, &lidar_);
}

void HybridMap::reportPhotometricError(VisualPoint& p, double mean_sq_error, double gate) {
  VisualMap& owner = isLongterm(p) ? longterm_visual_ : local_visual_;
  owner.reportPhotometricError(p, mean_sq_error, gate);
}

std::size_t HybridMap::removeBadPoints() {
  return local_visual_.removeBadPoints() + longterm_visual_.removeBadPoints();
}

std::size_t HybridMap::copyVisualPointsIn(const std::vector<VoxelKey>& visual_keys,
                                          std::vector<VisualPoint>& out) const {
  std::vector<VoxelKey> keys = visual_keys;
  std::sort(keys.begin(), keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
    return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
  });
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  const std::size_t before = out.size();
  const auto copy = [&out](const VisualPoint& p) { out.push_back(p); };
  for (const VoxelKey& k : keys) {
    local_visual_.forEachInVoxel(k, copy);
    longterm_visual_.forEachInVoxel(k, copy);
  }
  return out.size() - before;
}

bool HybridMap::upsertVisualPoint(VisualPoint p) {
  VisualMap* owner = &local_visual_;
  std::size_t old_obs = 0;
  if (auto old = local_visual_.extract(p.id)) {
    old_obs = old->obs.size();
  } else if (auto old_lt = longterm_visual_.extract(p.id)) {
    owner = &longterm_visual_;
    old_obs = old_lt->obs.size();
  }
  if (p.obs.empty()) return true;  // a removal
  if (!p.p_world.allFinite() || p.reference < -1 || p.reference >= int(p.obs.size())) return false;
  if (p.obs.size() > old_obs) obs_since_recount_ += p.obs.size() - old_obs;
  return owner->insert(std::make_unique<VisualPoint>(std::move(p)));
}

bool HybridMap::appendObservation(std::int64_t id, const VisualObservation& obs) {
  VisualMap* owner = &local_visual_;
  VisualPoint* p = local_visual_.find(id);
  if (p == nullptr) {
    owner = &longterm_visual_;
    p = longterm_visual_.find(id);
  }
  if (p == nullptr || p->converged) return false;
  p->obs.push_back(obs);
  p->last_seen = std::max(p->last_seen, obs.utime);
  ++obs_since_recount_;
  owner->refine(*p, &lidar_);
  return true;
}

HybridMapStats HybridMap::stats() const {
  HybridMapStats s;
  s.mode = cfg_.mode;
  s.local_voxels = lidar_.numRootVoxels();
  s.visual_points_local = local_visual_.size();
  s.visual_points_longterm = longterm_visual_.size();
  s.bytes_lidar = lidar_.bytes();
  s.bytes_visual_local = local_visual_.bytes() + local_visual_.scratchBytes();
  s.bytes_visual_longterm = longterm_visual_.bytes() + longterm_visual_.scratchBytes();
  s.bytes_index = tiles_.bytes() + pending_tiles_.capacity() * sizeof(VoxelKey) +
                  (pending_moves_.capacity() + pending_returns_.capacity() + pending_deletes_.capacity()) *
                      sizeof(std::int64_t) +
                  pending_evictions_.capacity() * sizeof(Victim) +
                  occupied_.capacity() / 8;
  s.bytes = s.bytes_lidar + s.bytes_visual_local + s.bytes_visual_longterm + s.bytes_index;
  s.cap_bytes = cfg_.mode == MapMode::Hybrid ? cfg_.capBytes() : 0;
  s.counters = counters_;
  return s;
}

std::size_t HybridMap::bytesEstimate() const {
  const double b = bytes_per_root_ * double(lidar_.numRootVoxels()) +
                   bytes_per_local_point_ * double(local_visual_.size()) +
                   bytes_per_longterm_point_ * double(longterm_visual_.size()) + double(fixed_bytes_) +
                   growth_per_point_ * double(points_since_recount_) +
                   double(obs_since_recount_ * sizeof(VisualObservation));
  return static_cast<std::size_t>(b);
}

std::size_t HybridMap::recount() {
  const HybridMapStats s = stats();
  // Growth inside existing root voxels (points collecting in leaves) is not in the per-root ratio:
  // learn it per inserted LiDAR point from what the estimate missed (smoothed, never negative).
  if (points_since_recount_ > 0) {
    const double missed = double(s.bytes) - double(bytesEstimate());
    const double rate = std::max(0.0, missed) / double(points_since_recount_);
    growth_per_point_ = counters_.recounts > 0 ? 0.5 * (growth_per_point_ + rate) : rate;
  }
  points_since_recount_ = 0;
  obs_since_recount_ = 0;
  // Bytes per item, without the scratch buffers (fixed); the index goes with the roots.
  const std::size_t scratch = local_visual_.scratchBytes() + longterm_visual_.scratchBytes();
  fixed_bytes_ = scratch;
  if (s.local_voxels > 0) bytes_per_root_ = double(s.bytes_lidar + s.bytes_index) / double(s.local_voxels);
  else fixed_bytes_ += s.bytes_lidar + s.bytes_index;
  if (s.visual_points_local > 0)
    bytes_per_local_point_ = double(s.bytes_visual_local - local_visual_.scratchBytes()) / double(s.visual_points_local);
  else fixed_bytes_ += s.bytes_visual_local - local_visual_.scratchBytes();
  if (s.visual_points_longterm > 0)
    bytes_per_longterm_point_ =
        double(s.bytes_visual_longterm - longterm_visual_.scratchBytes()) / double(s.visual_points_longterm);
  else fixed_bytes_ += s.bytes_visual_longterm - longterm_visual_.scratchBytes();
  updates_since_recount_ = 0;
  ++counters_.recounts;
  return s.bytes;
}

std::size_t HybridMap::pendingWork() const {
  return (pending_tiles_.size() - tile_cursor_) + (pending_moves_.size() - move_cursor_) +
         (pending_returns_.size() - return_cursor_) + (pending_deletes_.size() - delete_cursor_) +
         (pending_evictions_.size() - evict_cursor_);
}

void HybridMap::clear() {
  lidar_.clear();
  local_visual_.clear();
  longterm_visual_.clear();
  tiles_.clear();
  pending_tiles_.clear();
  pending_moves_.clear();
  pending_returns_.clear();
  pending_deletes_.clear();
  pending_evictions_.clear();
  tile_cursor_ = move_cursor_ = return_cursor_ = delete_cursor_ = evict_cursor_ = 0;
  started_ = false;
  occupied_.clear();
}

}  // namespace livo
