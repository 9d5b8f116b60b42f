// HybridMap: the parts' construction, the per-frame maintenance in order, the exact stats.
#include "livo/map/hybrid_map.hpp"

#include "livo/common/timing.hpp"

#include <algorithm>
#include <cmath>

namespace livo {

namespace {
int tileVoxels(const HybridMapConfig& c, const VoxelMapConfig& v) {
  return std::max(1, static_cast<int>(std::lround(c.tile_edge_m / v.voxel_size_m)));
}
}  // namespace

HybridMap::HybridMap(HybridMapConfig config, VoxelMapConfig lidar_config, VisualMapConfig visual_config)
    : cfg_((config.validate(), std::move(config))),
      lidar_(lidar_config, cfg_.mode == MapMode::Hybrid, tileVoxels(cfg_, lidar_config)),
      visual_(visual_config),
      slides_(cfg_),
      cap_(cfg_) {}

MapUpdateReport HybridMap::update(const Vec3& robot) {
  Stopwatch watch;
  MapUpdateReport rep;
  if (cfg_.mode != MapMode::Hybrid || !robot.allFinite()) {
    rep.bytes = bytesEstimate();
    return rep;
  }
  ++counters_.updates;
  MapWork work{lidar_, visual_, bytes_, rep, counters_};

  // 1. Start the slides that are due (the first call centres both cubes).
  slides_.startDue(robot, work);

  // 2. Pending work, bounded per update: evictions of an earlier cap event first (memory is the
  // hard limit), then slide work.
  WorkBudget budget = WorkBudget::perUpdate(cfg_.max_removals_per_update);
  cap_.evict(budget, work, 0.0);
  slides_.doPending(budget, work);

  // 3. Memory cap: an exact count when due, then evictions planned and started with what is left
  // of the budget.
  if (cap_.exactCountDue()) {
    bytes_.recount(lidar_, visual_, workBytes());
    ++counters_.recounts;
    rep.recounted = true;
  }
  cap_.enforce(robot, budget, work);

  rep.pending = slides_.pending() + cap_.pending();
  rep.bytes = bytesEstimate();
  rep.ms = watch.elapsedMs();
  counters_.max_update_ms = std::max(counters_.max_update_ms, rep.ms);
  if (rep.slid) counters_.max_slide_ms = std::max(counters_.max_slide_ms, rep.ms);
  return rep;
}

void HybridMap::finishPendingWork() {
  if (cfg_.mode != MapMode::Hybrid) return;
  WorkBudget budget = WorkBudget::none();
  MapUpdateReport rep;
  MapWork work{lidar_, visual_, bytes_, rep, counters_};
  cap_.evict(budget, work, 0.0);
  slides_.doPending(budget, work);
}

void HybridMap::setMemoryCapMb(double mb) {
  HybridMapConfig c = cfg_;
  c.memory_cap_mb = mb;
  c.validate();
  cfg_ = c;
  cap_.setCapBytes(cfg_.capBytes());
}

HybridMapStats HybridMap::stats() const {
  HybridMapStats s = ByteAccounting::count(lidar_, visual_, workBytes());
  s.mode = cfg_.mode;
  s.cap_bytes = cfg_.mode == MapMode::Hybrid ? cfg_.capBytes() : 0;
  s.counters = counters_;
  return s;
}

void HybridMap::clear() {
  lidar_.clear();
  visual_.clear();
  slides_.clear();
  cap_.clear();
}

}  // namespace livo
