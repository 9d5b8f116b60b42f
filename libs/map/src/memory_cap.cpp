// MemoryCap: the exact-count schedule, the eviction plan (farthest first) and the evictions.
#include "livo/map/memory_cap.hpp"

#include "livo/map/byte_accounting.hpp"
#include "livo/map/dual_visual_map.hpp"
#include "livo/map/local_lidar_map.hpp"

#include <algorithm>
#include <tuple>

namespace livo {

namespace {
// Heap blocks of a visual point besides VisualPoint::bytes(): the point and observation blocks, the
// id-hash node, the voxel-list slot (as counted by VisualMap::bytes()).
constexpr std::size_t kPointOverhead = 16 + 16 + 40 + 8;

double estimate(const MapWork& work) { return double(work.bytes.estimate(work.lidar, work.visual)); }
}  // namespace

MemoryCap::MemoryCap(const HybridMapConfig& config)
    : cap_bytes_(config.capBytes()),
      high_water_(config.cap_high_water),
      low_water_(config.cap_low_water),
      recount_interval_(config.recount_interval) {}

void MemoryCap::setCapBytes(std::size_t cap_bytes) {
  cap_bytes_ = cap_bytes;
  calibrated_ = false;  // count exactly at the next check
  if (cap_bytes_ == 0) std::vector<Victim>().swap(pending_evictions_), evict_cursor_ = 0;
}

bool MemoryCap::exactCountDue() {
  if (cap_bytes_ == 0) return false;
  // Exact count (a walk: the expensive part) at the first check, after each completed eviction (its
  // per-root sizes are averages: far roots are lighter) and every recount_interval checks (roots grow
  // as points arrive: the estimate falls behind); the O(1) estimate in between.
  ++checks_since_count_;
  if (calibrated_ && checks_since_count_ < recount_interval_) return false;
  checks_since_count_ = 0;
  calibrated_ = true;
  return true;
}

void MemoryCap::enforce(const Vec3& robot, WorkBudget& budget, MapWork& work) {
  if (cap_bytes_ == 0) return;
  const double cap = double(cap_bytes_), high = high_water_ * cap, low = low_water_ * cap;
  const bool evicting = evict_cursor_ < pending_evictions_.size();
  if (!evicting && estimate(work) > high) {
    ++work.total.eviction_events;
    plan(robot, work, estimate(work) - low);
  }
  evict(budget, work, 0.0);
  // Hard limit: over the cap itself, evict beyond the budget down to the low-water mark (the margin
  // covers the estimate's bias: far root voxels are lighter than the average used for them; with the
  // patches as bytes the root voxels are most of the bytes, and the high-water mark left the exact
  // count 3 % over the cap in HybridMap.EvictionIsSpreadOverUpdatesWithinTheBudgetBelowTheCap).
  for (int round = 0; round < 2 && estimate(work) > cap; ++round) {
    if (evict_cursor_ >= pending_evictions_.size()) {
      ++work.total.eviction_events;
      plan(robot, work, estimate(work) - low);
    }
    WorkBudget unlimited = WorkBudget::none();
    evict(unlimited, work, low);
  }
}

void MemoryCap::plan(const Vec3& robot, const MapWork& work, double need) {
  // Victims farthest first until `need` bytes (exact per visual point, the calibrated bytes per root
  // voxel), through max-heaps: O(n + k log n) for k victims.
  pending_evictions_.clear();
  evict_cursor_ = 0;

  // a) Long-term visual points, farthest first (ties: larger id first, deterministic).
  const VisualMap& longterm = work.visual.longterm();
  if (longterm.size() > 0) {
    std::vector<std::tuple<double, std::int64_t, std::size_t>> heap;  // (dist^2, id, bytes)
    heap.reserve(longterm.size());
    longterm.forEach([&](const VisualPoint& p) {
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
  // b) Then the local content.
  planLocal(robot, work, need);
}

void MemoryCap::planLocal(const Vec3& robot, const MapWork& work, double need) {
  // Root voxels (by centre) and local visual points (by position) in one order, farthest first.
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
  const RootTileIndex& roots = work.lidar.tiles();
  const VisualMap& local = work.visual.local();
  std::vector<Item> heap;
  heap.reserve(roots.size() + local.size());
  const double s = work.lidar.voxels().config().voxel_size_m;
  const double bytes_per_root = work.bytes.bytesPerRoot();
  roots.forEachRoot([&](const VoxelKey& k) {
    heap.push_back({(k.center(s) - robot).squaredNorm(), false, k, 0, bytes_per_root});
  });
  local.forEach([&](const VisualPoint& p) {
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

void MemoryCap::evict(WorkBudget& budget, MapWork& work, double stop_below) {
  while (evict_cursor_ < pending_evictions_.size() && !(stop_below > 0.0 && estimate(work) <= stop_below) &&
         budget.take()) {
    const Victim& v = pending_evictions_[evict_cursor_++];
    switch (v.kind) {
      case Victim::LongtermPoint:
        if (work.visual.longterm().extract(v.id)) {
          ++work.rep.evicted_longterm_points;
          ++work.total.evicted_longterm_points;
        }
        break;
      case Victim::LocalPoint:
        if (work.visual.local().extract(v.id)) {
          ++work.rep.evicted_local_points;
          ++work.total.evicted_local_points;
        }
        break;
      case Victim::Root:
        if (work.lidar.removeRoot(v.key)) {
          ++work.rep.evicted_local_voxels;
          ++work.total.evicted_local_voxels;
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

void MemoryCap::clear() {
  pending_evictions_.clear();
  evict_cursor_ = 0;
}

}  // namespace livo
