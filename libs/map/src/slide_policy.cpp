// SlidePolicy: starting the slides of the local and long-term cubes and doing their work lists.
#include "livo/map/slide_policy.hpp"

#include "livo/map/dual_visual_map.hpp"
#include "livo/map/local_lidar_map.hpp"

#include <algorithm>
#include <memory>

namespace livo {

namespace {
bool outsideCube(const Vec3& c, const Vec3& center, double half_edge) {
  return ((c - center).cwiseAbs().array() > half_edge).any();
}
}  // namespace

SlidePolicy::SlidePolicy(const HybridMapConfig& config)
    : local_edge_m_(config.local_edge_m),
      slide_distance_m_(config.slide_distance_m),
      longterm_edge_m_(config.longterm_edge_m),
      longterm_slide_m_(config.longterm_slide_m),
      longterm_reference_only_(config.longterm_reference_only),
      longterm_enabled_(config.longterm_enabled),
      longterm_per_voxel_(config.longterm_points_per_voxel),
      longterm_min_obs_(config.longterm_min_observations) {}

bool SlidePolicy::outsideLocal(const Vec3& c) const { return outsideCube(c, local_center_, 0.5 * local_edge_m_); }

bool SlidePolicy::outsideLongterm(const Vec3& c) const {
  return outsideCube(c, longterm_center_, 0.5 * longterm_edge_m_);
}

void SlidePolicy::startDue(const Vec3& robot, MapWork& work) {
  if (!started_ || (robot - longterm_center_).norm() >= longterm_slide_m_) {
    startLongterm(robot, work);
    work.rep.longterm_slid = true;
  }
  if (!started_ || (robot - local_center_).norm() >= slide_distance_m_) startLocal(robot, work);
  started_ = true;
}

void SlidePolicy::startLocal(const Vec3& center, MapWork& work) {
  local_center_ = center;
  ++work.total.slides;
  work.rep.slid = true;
  const double half = 0.5 * local_edge_m_;
  // Work lists are rebuilt from scratch: leftovers of the previous slide are found again.
  pending_tiles_ = work.lidar.tiles().tilesReachingOutside(center, half);
  tile_cursor_ = 0;
  pending_moves_ = work.visual.local().idsOutsideBox(center, half);
  move_cursor_ = 0;
  pending_returns_.clear();
  return_cursor_ = 0;
  const VisualMap& longterm = work.visual.longterm();
  const double vs = longterm.config().voxel_size_m;
  longterm.forEach([&](const VisualPoint& p) {
    if (!outsideLocal(longterm.keyOf(p.p_world).center(vs))) pending_returns_.push_back(p.id);
  });
  std::sort(pending_returns_.begin(), pending_returns_.end());
}

void SlidePolicy::startLongterm(const Vec3& center, MapWork& work) {
  longterm_center_ = center;
  ++work.total.longterm_slides;
  pending_deletes_ = work.visual.longterm().idsOutsideBox(center, 0.5 * longterm_edge_m_);
  delete_cursor_ = 0;
}

bool SlidePolicy::longtermVoxelFull(const VisualPoint& p, MapWork& work) const {
  if (longterm_per_voxel_ <= 0) return false;
  const VisualMap& longterm = work.visual.longterm();
  int n = 0;
  longterm.forEachInVoxel(longterm.keyOf(p.p_world), [&n](const VisualPoint&) { ++n; });
  return n >= longterm_per_voxel_;
}

bool SlidePolicy::moveToLongterm(std::int64_t id, MapWork& work) {
  VisualMap& local = work.visual.local();
  const VisualPoint* q = local.find(id);
  if (q == nullptr) return false;
  const Vec3 c = local.keyOf(q->p_world).center(local.config().voxel_size_m);
  if (!outsideLocal(c)) return false;  // judged again: the cube may have moved since the list was made
  std::unique_ptr<VisualPoint> p = local.extract(id);
  // Only points with a patch, seen often enough, are worth keeping; beyond the long-term cube (or
  // without a long-term map) nothing is kept.
  if (!longterm_enabled_ || p->referenceObs() == nullptr || p->viewCount() < longterm_min_obs_ ||
      outsideLongterm(c) || longtermVoxelFull(*p, work)) {
    ++work.rep.deleted_points;
    ++work.total.deleted_points;
    return true;
  }
  if (longterm_reference_only_ && p->obs.size() > 1) {
    std::vector<VisualObservation> ref{p->obs[std::size_t(p->reference)]};
    p->obs.swap(ref);
    p->reference = 0;
  }
  p->obs.shrink_to_fit();
  if (!work.visual.longterm().insert(std::move(p))) {
    ++work.rep.deleted_points;
    ++work.total.deleted_points;
    return true;
  }
  ++work.rep.moved_to_longterm;
  ++work.total.moved_to_longterm;
  return true;
}

void SlidePolicy::doPending(WorkBudget& budget, MapWork& work) {
  VisualMap& local = work.visual.local();
  VisualMap& longterm = work.visual.longterm();
  // Visual points leaving the local cube.
  while (move_cursor_ < pending_moves_.size() && budget.take()) moveToLongterm(pending_moves_[move_cursor_++], work);
  // Long-term points back inside the local cube (revisits).
  const double vs = local.config().voxel_size_m;
  while (return_cursor_ < pending_returns_.size() && budget.take()) {
    const std::int64_t id = pending_returns_[return_cursor_++];
    const VisualPoint* q = longterm.find(id);
    if (q == nullptr || outsideLocal(longterm.keyOf(q->p_world).center(vs))) continue;
    if (local.insert(longterm.extract(id))) {
      ++work.rep.moved_to_local;
      ++work.total.moved_to_local;
    }
  }
  // Long-term points beyond the long-term cube.
  while (delete_cursor_ < pending_deletes_.size() && budget.take()) {
    const std::int64_t id = pending_deletes_[delete_cursor_++];
    const VisualPoint* q = longterm.find(id);
    if (q == nullptr || !outsideLongterm(longterm.keyOf(q->p_world).center(vs))) continue;
    longterm.extract(id);
    ++work.rep.deleted_points;
    ++work.total.deleted_points;
  }
  // LiDAR root voxels outside the local cube, tile by tile (a tile may be resumed in the next update).
  const auto leaves = [this](const Vec3& root_center) { return outsideLocal(root_center); };
  while (tile_cursor_ < pending_tiles_.size() && !budget.exhausted()) {
    bool done = false;
    const std::size_t removed = work.lidar.removeRootsOf(pending_tiles_[tile_cursor_], leaves, budget.remaining(), done);
    budget.spend(removed);
    work.rep.removed_voxels += removed;
    work.total.removed_voxels += removed;
    if (!done) break;
    ++tile_cursor_;
  }
  // Release finished lists (swap: clear() would keep the capacity).
  if (move_cursor_ == pending_moves_.size()) std::vector<std::int64_t>().swap(pending_moves_), move_cursor_ = 0;
  if (return_cursor_ == pending_returns_.size()) std::vector<std::int64_t>().swap(pending_returns_), return_cursor_ = 0;
  if (delete_cursor_ == pending_deletes_.size()) std::vector<std::int64_t>().swap(pending_deletes_), delete_cursor_ = 0;
  if (tile_cursor_ == pending_tiles_.size()) std::vector<VoxelKey>().swap(pending_tiles_), tile_cursor_ = 0;
}

std::size_t SlidePolicy::pending() const {
  return (pending_tiles_.size() - tile_cursor_) + (pending_moves_.size() - move_cursor_) +
         (pending_returns_.size() - return_cursor_) + (pending_deletes_.size() - delete_cursor_);
}

std::size_t SlidePolicy::workBytes() const {
  return pending_tiles_.capacity() * sizeof(VoxelKey) +
         (pending_moves_.capacity() + pending_returns_.capacity() + pending_deletes_.capacity()) * sizeof(std::int64_t);
}

void SlidePolicy::clear() {
  pending_tiles_.clear();
  pending_moves_.clear();
  pending_returns_.clear();
  pending_deletes_.clear();
  tile_cursor_ = move_cursor_ = return_cursor_ = delete_cursor_ = 0;
  started_ = false;
}

}  // namespace livo
