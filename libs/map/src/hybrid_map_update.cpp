// HybridMap maintenance: slides of the local and long-term cubes (incremental, budgeted per update)
// and the memory cap (farthest long-term visual points first, then the farthest local content).
#include "livo/map/hybrid_map.hpp"

#include "livo/common/timing.hpp"

#include <algorithm>
#include <tuple>

namespace livo {

namespace {
// Heap blocks of a visual point besides VisualPoint::bytes(): the point and observation blocks, the
// id-hash node, the voxel-list slot (as counted by VisualMap::bytes()).
constexpr std::size_t kPointOverhead = 16 + 16 + 40 + 8;

bool outsideCube(const Vec3& c, const Vec3& center, double half_edge) {
  return ((c - center).cwiseAbs().array() > half_edge).any();
}
}  // namespace

bool HybridMap::outsideLocal(const Vec3& c) const { return outsideCube(c, local_center_, 0.5 * cfg_.local_edge_m); }

bool HybridMap::outsideLongterm(const Vec3& c) const {
  return outsideCube(c, longterm_center_, 0.5 * cfg_.longterm_edge_m);
}

MapUpdateReport HybridMap::update(const Vec3& robot) {
  Stopwatch watch;
  MapUpdateReport rep;
  if (cfg_.mode != MapMode::Hybrid || !robot.allFinite()) {
    rep.bytes = bytesEstimate();
    return rep;
  }
  ++counters_.updates;

  // 1. Start the slides that are due (the first call centres both cubes). Long-term first, so that
  // points leaving the local cube are judged against the new long-term cube.
  if (!started_ || (robot - longterm_center_).norm() >= cfg_.longterm_slide_m) {
    startLongtermSlide(robot);
    rep.longterm_slid = true;
  }
  if (!started_ || (robot - local_center_).norm() >= cfg_.slide_distance_m) startLocalSlide(robot, rep);
  started_ = true;

  // 2. Pending work, bounded per update: evictions of an earlier cap event first (memory is the
  // hard limit), then slide work.
  Budget budget{std::size_t(cfg_.max_removals_per_update), cfg_.max_removals_per_update == 0};
  doEvictions(budget, rep, 0.0);
  doPendingWork(budget, rep);

  // 3. Memory cap: may plan evictions and start them with what is left of the budget.
  enforceCap(robot, budget, rep);

  rep.pending = pendingWork();
  rep.bytes = bytesEstimate();
  rep.ms = watch.elapsedMs();
  counters_.max_update_ms = std::max(counters_.max_update_ms, rep.ms);
  if (rep.slid) counters_.max_slide_ms = std::max(counters_.max_slide_ms, rep.ms);
  return rep;
}

void HybridMap::setMemoryCapMb(double mb) {
  HybridMapConfig c = cfg_;
  c.memory_cap_mb = mb;
  c.validate();
  cfg_ = c;
  calibrated_ = false;  // count exactly at the next update
  if (cfg_.capBytes() == 0) std::vector<Victim>().swap(pending_evictions_), evict_cursor_ = 0;
}

void HybridMap::finishPendingWork() {
  if (cfg_.mode != MapMode::Hybrid) return;
  Budget budget{0, true};
  MapUpdateReport rep;
  doEvictions(budget, rep, 0.0);
  doPendingWork(budget, rep);
}

void HybridMap::startLocalSlide(const Vec3& center, MapUpdateReport& rep) {
  local_center_ = center;
  ++counters_.slides;
  rep.slid = true;
  const double half = 0.5 * cfg_.local_edge_m;
  // Work lists are rebuilt from scratch: leftovers of the previous slide are found again.
  pending_tiles_ = tiles_.tilesReachingOutside(center, half);
  tile_cursor_ = 0;
  pending_moves_ = local_visual_.idsOutsideBox(center, half);
  move_cursor_ = 0;
  pending_returns_.clear();
  return_cursor_ = 0;
  const double vs = longterm_visual_.config().voxel_size_m;
  longterm_visual_.forEach([&](const VisualPoint& p) {
    if (!outsideLocal(longterm_visual_.keyOf(p.p_world).center(vs))) pending_returns_.push_back(p.id);
  });
  std::sort(pending_returns_.begin(), pending_returns_.end());
}

void HybridMap::startLongtermSlide(const Vec3& center) {
  longterm_center_ = center;
  ++counters_.longterm_slides;
  pending_deletes_ = longterm_visual_.idsOutsideBox(center, 0.5 * cfg_.longterm_edge_m);
  delete_cursor_ = 0;
}

bool HybridMap::moveToLongterm(std::int64_t id, MapUpdateReport& rep) {
  const VisualPoint* q = local_visual_.find(id);
  if (q == nullptr) return false;
  const Vec3 c = local_visual_.keyOf(q->p_world).center(local_visual_.config().voxel_size_m);
  if (!outsideLocal(c)) return false;  // judged again: the cube may have moved since the list was made
  std::unique_ptr<VisualPoint> p = local_visual_.extract(id);
  // Only points with a patch are worth keeping; beyond the long-term cube nothing is kept.
  if (p->referenceObs() == nullptr || outsideLongterm(c)) {
    ++rep.deleted_points;
    ++counters_.deleted_points;
    return true;
  }
  if (cfg_.longterm_reference_only && p->obs.size() > 1) {
    std::vector<VisualObservation> ref{p->obs[std::size_t(p->reference)]};
    p->obs.swap(ref);
    p->reference = 0;
  }
  p->obs.shrink_to_fit();
  if (!longterm_visual_.insert(std::move(p))) {
    ++rep.deleted_points;
    ++counters_.deleted_points;
    return true;
  }
  ++rep.moved_to_longterm;
  ++counters_.moved_to_longterm;
  return true;
}

void HybridMap::doPendingWork(Budget& budget, MapUpdateReport& rep) {
  // Visual points leaving the local cube.
  while (move_cursor_ < pending_moves_.size() && budget.take()) moveToLongterm(pending_moves_[move_cursor_++], rep);
  // Long-term points back inside the local cube (revisits).
  const double vs = local_visual_.config().voxel_size_m;
  while (return_cursor_ < pending_returns_.size() && budget.take()) {
    const std::int64_t id = pending_returns_[return_cursor_++];
    const VisualPoint* q = longterm_visual_.find(id);
    if (q == nullptr || outsideLocal(longterm_visual_.keyOf(q->p_world).center(vs))) continue;
    if (local_visual_.insert(longterm_visual_.extract(id))) {
      ++rep.moved_to_local;
      ++counters_.moved_to_local;
    }
  }
  // Long-term points beyond the long-term cube.
  while (delete_cursor_ < pending_deletes_.size() && budget.take()) {
    const std::int64_t id = pending_deletes_[delete_cursor_++];
    const VisualPoint* q = longterm_visual_.find(id);
    if (q == nullptr || !outsideLongterm(longterm_visual_.keyOf(q->p_world).center(vs))) continue;
    longterm_visual_.extract(id);
    ++rep.deleted_points;
    ++counters_.deleted_points;
  }
  // LiDAR root voxels outside the local cube, tile by tile (a tile may be resumed in the next update).
  const double s = lidar_.config().voxel_size_m;
  while (tile_cursor_ < pending_tiles_.size() && !budget.exhausted()) {
    const VoxelKey tile = pending_tiles_[tile_cursor_];
    RootTileIndex::RootSet* roots = tiles_.roots(tile);
    if (roots == nullptr) {
      ++tile_cursor_;
      continue;
    }
    std::size_t removed = 0;
    auto it = roots->begin();
    while (it != roots->end()) {
      if (!outsideLocal(it->center(s))) {
        ++it;
        continue;
      }
      if (!budget.take()) break;
      lidar_.removeVoxel(*it);
      it = roots->erase(it);
      ++removed;
    }
    const bool done = it == roots->end();
    tiles_.noteRemoved(removed);
    rep.removed_voxels += removed;
    counters_.removed_voxels += removed;
    if (!done) break;
    tiles_.dropIfEmpty(tile);
    ++tile_cursor_;
  }
  // Release finished lists (swap: clear() would keep the capacity).
  if (move_cursor_ == pending_moves_.size()) std::vector<std::int64_t>().swap(pending_moves_), move_cursor_ = 0;
  if (return_cursor_ == pending_returns_.size()) std::vector<std::int64_t>().swap(pending_returns_), return_cursor_ = 0;
  if (delete_cursor_ == pending_deletes_.size()) std::vector<std::int64_t>().swap(pending_deletes_), delete_cursor_ = 0;
  if (tile_cursor_ == pending_tiles_.size()) std::vector<VoxelKey>().swap(pending_tiles_), tile_cursor_ = 0;
}

void HybridMap::enforceCap(const Vec3& robot, Budget& budget, MapUpdateReport& rep) {
  const std::size_t cap = cfg_.capBytes();
  if (cap == 0) return;
  const double high = cfg_.cap_high_water * double(cap), low = cfg_.cap_low_water * double(cap);
  // Exact count (a walk: the expensive part) at the first check, after each completed eviction (its
  // per-root sizes are averages: far roots are lighter) and every recount_interval updates (roots
  // grow as points arrive: the estimate falls behind); the O(1) estimate in between.
  ++updates_since_recount_;
  if (!calibrated_ || updates_since_recount_ >= cfg_.recount_interval) {
    recount();
    calibrated_ = true;
    rep.recounted = true;
  }
  const bool evicting = evict_cursor_ < pending_evictions_.size();
  if (!evicting && double(bytesEstimate()) > high) {
    ++counters_.eviction_events;
    planEvictions(robot, double(bytesEstimate()) - low);
  }
  doEvictions(budget, rep, 0.0);
  // Hard limit: over the cap itself, evict beyond the budget down to the high-water mark (the margin
  // covers the estimate's bias: far root voxels are lighter than the average used for them).
  for (int round = 0; round < 2 && double(bytesEstimate()) > double(cap); ++round) {
    if (evict_cursor_ >= pending_evictions_.size()) {
      ++counters_.eviction_events;
      planEvictions(robot, double(bytesEstimate()) - low);
    }
    Budget unlimited{0, true};
    doEvictions(unlimited, rep, high);
  }
}

void HybridMap::planEvictions(const Vec3& robot, double need) {
  // Victims farthest first until `need` bytes (exact per visual point, the calibrated bytes per root
  // voxel), through max-heaps: O(n + k log n) for k victims.
  pending_evictions_.clear();
  evict_cursor_ = 0;

  // a) Long-term visual points, farthest first (ties: larger id first, deterministic).
  if (longterm_visual_.size() > 0) {
    std::vector<std::tuple<double, std::int64_t, std::size_t>> heap;  // (dist^2, id, bytes)
    heap.reserve(longterm_visual_.size());
    longterm_visual_.forEach([&](const VisualPoint& p) {
      heap.emplace_back((p.p_world - robot).squaredNorm(), p.id, p.bytes() + kPointOverhead);
    });
    std::make_heap(heap.begin(), heap.end());
    while (need > 0 && !heap.empty()) {
      std::pop_heap(heap.begin(), heap.end());
      pending_evictions_.push_back({Victim::LongtermPoint, VoxelKey{}, std::get<1>(heap.back())});
      need -= double(std::get<2>(heap.back()));
      heap.pop_back();
    }
  }
  if (need <= 0) return;

  // b) Local content, farthest first: root voxels (by centre) and local visual points (by position).
  struct Item {
    double d2;
    bool is_point;
    VoxelKey key;
    std::int64_t id;
    double bytes;
    bool operator<(const Item& o) const {  // heap order: farthest on top; ties points, then larger keys
      if (d2 != o.d2) return d2 < o.d2;
      if (is_point != o.is_point) return !is_point;
      return is_point ? id < o.id : std::tie(key.x, key.y, key.z) < std::tie(o.key.x, o.key.y, o.key.z);
    }
  };
  std::vector<Item> heap;
  heap.reserve(tiles_.size() + local_visual_.size());
  const double s = lidar_.config().voxel_size_m;
  tiles_.forEachRoot([&](const VoxelKey& k) {
    heap.push_back({(k.center(s) - robot).squaredNorm(), false, k, 0, bytes_per_root_});
  });
  local_visual_.forEach([&](const VisualPoint& p) {
    heap.push_back({(p.p_world - robot).squaredNorm(), true, VoxelKey{}, p.id, double(p.bytes() + kPointOverhead)});
  });
  std::make_heap(heap.begin(), heap.end());
  while (need > 0 && !heap.empty()) {
    std::pop_heap(heap.begin(), heap.end());
    const Item& it = heap.back();
    pending_evictions_.push_back({it.is_point ? Victim::LocalPoint : Victim::Root, it.key, it.id});
    need -= it.bytes;
    heap.pop_back();
  }
}

void HybridMap::doEvictions(Budget& budget, MapUpdateReport& rep, double stop_below) {
  while (evict_cursor_ < pending_evictions_.size() && !(stop_below > 0.0 && double(bytesEstimate()) <= stop_below) &&
         budget.take()) {
    const Victim& v = pending_evictions_[evict_cursor_++];
    switch (v.kind) {
      case Victim::LongtermPoint:
        if (longterm_visual_.extract(v.id)) {
          ++rep.evicted_longterm_points;
          ++counters_.evicted_longterm_points;
        }
        break;
      case Victim::LocalPoint:
        if (local_visual_.extract(v.id)) {
          ++rep.evicted_local_points;
          ++counters_.evicted_local_points;
        }
        break;
      case Victim::Root:
        if (lidar_.removeVoxel(v.key) > 0) {
          tiles_.remove(v.key);
          ++rep.evicted_local_voxels;
          ++counters_.evicted_local_voxels;
        }
        break;
    }
  }
  if (evict_cursor_ == pending_evictions_.size() && !pending_evictions_.empty()) {
    std::vector<Victim>().swap(pending_evictions_);
    evict_cursor_ = 0;
    calibrated_ = false;  // count exactly at the next check
  }
}

}  // namespace livo
