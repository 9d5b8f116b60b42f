// Hybrid map over long drives: bytes flatten in hybrid mode while the global map grows, and the time
// of a slide on a large street map (printed; not asserted).
#include "livo/common/timing.hpp"
#include "livo/map/hybrid_map.hpp"
#include "map_hybrid_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

using namespace livo;
using namespace livo::test;

namespace {

// A synthetic 3 km drive along +x in 2 m steps: per step the LiDAR sees a new 2 m slab 40 m ahead
// (ground strip and a wall, 0.5 m voxels: 24 root voxels with a plane each) and three new visual
// points with one observation. Returns the exact bytes after each step in `bytes` (every `every` steps).
struct DriveResult {
  std::vector<std::size_t> bytes;  ///< stats().bytes at steps every-1, 2 every-1, ...
  std::size_t max_report_bytes = 0;
  HybridMapCounters counters;
};

DriveResult drive(MapMode mode, double cap_mb, int steps, int every) {
  HybridMapConfig cfg;
  cfg.mode = mode;
  cfg.memory_cap_mb = cap_mb;
  HybridMap map(cfg, VoxelMapConfig{}, VisualMapConfig{});
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 2.0);
  DriveResult out;
  std::int64_t id = 1;
  for (int step = 0; step < steps; ++step) {
    const double x = 2.0 * step;
    std::vector<PointWithCov> pts;
    groundPatch(pts, x + 40, x + 42, -1, 1, 0.2, 0.5, rng);
    wallPatch(pts, x + 40, x + 42, 2.1, 0, 1, 0.5, rng);
    map.lidar().insert(pts);
    for (int i = 0; i < 3; ++i) map.visual().local().insert(visualPoint(id++, Vec3(x + 40 + u(rng), 2.05, 0.2 + 0.3 * i)));
    const MapUpdateReport rep = map.update(Vec3(x, 0, 0));
    out.max_report_bytes = std::max(out.max_report_bytes, rep.bytes);
    if ((step + 1) % every == 0) out.bytes.push_back(map.stats().bytes);
  }
  out.counters = map.counters();
  return out;
}

}  // namespace

TEST(HybridMap, LongDriveHybridBytesFlattenWhileGlobalGrows) {
  const int steps = 1500, every = 100;  // 3 km; bytes every 200 m
  const DriveResult hybrid = drive(MapMode::Hybrid, 0.0, steps, every);
  const DriveResult global = drive(MapMode::Global, 0.0, steps, every);
  const std::size_t third = std::size_t(steps / 3 / every) - 1;  // 1 km
  std::cout << "km    hybrid MB   global MB\n";
  for (std::size_t i = 0; i < hybrid.bytes.size(); ++i)
    std::cout << 0.2 * double(i + 1) << "  " << double(hybrid.bytes[i]) / 1048576.0 << "  "
              << double(global.bytes[i]) / 1048576.0 << "\n";
  const double h_third = double(hybrid.bytes[third]), h_end = double(hybrid.bytes.back());
  const double g_third = double(global.bytes[third]), g_end = double(global.bytes.back());
  EXPECT_NEAR(h_end, h_third, 0.10 * h_third) << "hybrid bytes flatten";
  EXPECT_GT(g_end, 2.0 * g_third) << "global bytes keep growing";
  EXPECT_LE(h_end, 0.5 * g_end);
  EXPECT_EQ(global.counters.slides, 0u);
  std::cout << "hybrid: " << hybrid.counters.slides << " slides, " << hybrid.counters.longterm_slides
            << " long-term slides, worst update " << hybrid.counters.max_update_ms << " ms\n";

  // With a cap of 60% of the uncapped steady state, every update reports bytes under the cap and the
  // exact count every 200 m is under it too.
  const double cap_mb = 0.6 * h_end / 1048576.0;
  const DriveResult capped = drive(MapMode::Hybrid, cap_mb, steps, every);
  const std::size_t cap = static_cast<std::size_t>(cap_mb * 1048576.0);
  EXPECT_LE(capped.max_report_bytes, cap);
  for (const std::size_t b : capped.bytes) EXPECT_LE(b, cap);
  EXPECT_GT(capped.counters.eviction_events, 0u);
  std::cout << "capped at " << cap_mb << " MB: " << capped.counters.eviction_events << " eviction events, "
            << capped.counters.evicted_longterm_points << " long-term points, " << capped.counters.evicted_local_voxels
            << " voxels, " << capped.counters.evicted_local_points << " local points evicted, "
            << capped.counters.recounts << " exact counts, worst update " << capped.counters.max_update_ms << " ms\n";
}

TEST(HybridMap, SlideTimeOnALargeStreetMap) {
  // A 260 m street with 0.5 m voxels: ground |y| < 10 and two 10 m walls, about 42k root voxels (each a plane).
  std::mt19937 rng(23);
  std::vector<PointWithCov> pts;
  groundPatch(pts, 0, 260, -10, 10, 0.2, 0.5, rng);
  wallPatch(pts, 0, 260, 10.1, 0, 10, 0.5, rng);
  wallPatch(pts, 0, 260, -10.1, 0, 10, 0.5, rng);
  const auto time_slide = [&](int budget, std::size_t* roots_after) {
    HybridMapConfig cfg;
    cfg.max_removals_per_update = budget;
    HybridMap map(cfg, VoxelMapConfig{}, VisualMapConfig{});
    map.lidar().insert(pts);
    double worst_first = 0.0, worst_slide = 0.0;
    int updates = 0;
    // First update at x = 130: the 200 m cube drops 30 m at each end; then a 20 m slide to x = 150.
    for (MapUpdateReport r = map.update(Vec3(130, 0, 0));; r = map.update(Vec3(130, 0, 0))) {
      worst_first = std::max(worst_first, r.ms);
      if (budget > 0) {
        EXPECT_LE(r.removed_voxels, std::size_t(budget));
      }
      if (r.pending == 0) break;
    }
    const std::size_t before = map.lidar().voxels().numRootVoxels();
    for (MapUpdateReport r = map.update(Vec3(150, 0, 0));; r = map.update(Vec3(150, 0, 0))) {
      worst_slide = std::max(worst_slide, r.ms);
      ++updates;
      if (r.pending == 0) break;
    }
    Stopwatch w;
    const HybridMapStats s = map.stats();
    std::cout << "budget " << budget << ": first centring worst update " << worst_first << " ms; 20 m slide ("
              << before - s.local_voxels << " of " << before << " root voxels) over " << updates
              << " updates, worst " << worst_slide << " ms; exact count of " << s.bytes / 1048576.0 << " MB in "
              << w.elapsedMs() << " ms\n";
    *roots_after = s.local_voxels;
  };
  std::size_t budgeted = 0, whole = 0;
  time_slide(1000, &budgeted);
  time_slide(0, &whole);
  EXPECT_EQ(budgeted, whole);
  // Reference: VoxelMap::removeOutsideBox (a full hash scan and all erasures in one call).
  VoxelMap plain;
  plain.insert(pts);
  plain.removeOutsideBox(Vec3(130, 0, 0), 100.0);
  Stopwatch w;
  const std::size_t removed = plain.removeOutsideBox(Vec3(150, 0, 0), 100.0);
  std::cout << "VoxelMap::removeOutsideBox: 20 m slide (" << removed << " root voxels) in " << w.elapsedMs() << " ms\n";
  EXPECT_EQ(plain.numRootVoxels(), whole);
}
