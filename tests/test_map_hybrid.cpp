// libs/map hybrid map: sliding (local voxels and visual points against a brute-force cube test over
// everything inserted, incremental under a per-update budget, long-term deletion, revisits), the
// memory cap (bytes under the cap, eviction order farthest first against brute-force distances,
// long-term before local), global mode, retrieval from both visual maps, byte accounting, a 3 km
// long drive and slide timing: test_map_hybrid_drive.cpp.
#include "livo/common/timing.hpp"
#include "livo/map/hybrid_map.hpp"
#include "livo/sensors/camera_model.hpp"
#include "map_hybrid_test_util.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <tuple>

using namespace livo;
using namespace livo::test;

namespace {

using KeyT = std::tuple<std::int64_t, std::int64_t, std::int64_t>;
KeyT tup(const VoxelKey& k) { return {k.x, k.y, k.z}; }

bool outside(const Vec3& c, const Vec3& center, double half) { return ((c - center).cwiseAbs().array() > half).any(); }


std::set<KeyT> rootKeysWithPlanes(const VoxelMap& m) {
  std::set<KeyT> keys;
  m.forEachPlane([&](const VoxelKey& k, const Plane&) { keys.insert(tup(k)); });
  return keys;
}

std::set<std::int64_t> ids(const VisualMap& m) {
  std::set<std::int64_t> out;
  m.forEach([&](const VisualPoint& p) { out.insert(p.id); });
  return out;
}

// Small cubes for fast tests: local 40 m (slid every 5 m), long-term 100 m (slid every 10 m), 1 m voxels.
HybridMapConfig smallConfig() {
  HybridMapConfig c;
  c.local_edge_m = 40.0;
  c.slide_distance_m = 5.0;
  c.longterm_edge_m = 100.0;
  c.longterm_slide_m = 10.0;
  c.tile_edge_m = 4.0;
  c.max_removals_per_update = 0;
  c.longterm_min_observations = 1;  // the slide model keeps every point with a reference
  return c;
}

VoxelMapConfig voxels1m() {
  VoxelMapConfig v;
  v.voxel_size_m = 1.0;
  return v;
}

// A scene on [-60, 60]^2: ground roots everywhere, visual points on a grid (every 7th without a reference).
struct Scene {
  std::set<KeyT> roots;
  std::map<std::int64_t, std::pair<Vec3, bool>> points;  // id -> (position, has reference)
};

Scene fillScene(HybridMap& map, unsigned seed) {
  Scene sc;
  std::mt19937 rng(seed);
  std::vector<PointWithCov> pts;
  groundPatch(pts, -60, 60, -60, 60, 0.3, 1.0, rng);
  EXPECT_EQ(map.lidar().insert(pts), pts.size());
  for (const auto& p : pts) sc.roots.insert(tup(map.lidar().voxels().keyOf(p.p_world)));
  std::uniform_real_distribution<double> u(-59, 59);
  for (std::int64_t id = 1; id <= 3000; ++id) {
    const Vec3 p(u(rng), u(rng), 1.0 + 0.01 * double(id % 50));
    const bool ref = id % 7 != 0;
    EXPECT_TRUE(map.visual().local().insert(visualPoint(id, p, ref, 1 + int(id % 4))));
    sc.points[id] = {p, ref};
  }
  return sc;
}

// Brute-force model of the slide rules over everything inserted, applied at every slide the map reports:
// long-term points leaving the long-term cube are deleted; then root voxels and local points leaving
// the local cube are deleted / moved (points with a reference inside the long-term cube) and long-term
// points inside the local cube come back. Cubes are tested on voxel centres.
struct SlideModel {
  std::set<KeyT> roots;
  std::map<std::int64_t, std::pair<Vec3, bool>> local, longterm;
  double lidar_voxel = 1.0, visual_voxel = 0.5, local_half = 20.0, lt_half = 50.0;
  std::size_t lt_deleted = 0;  ///< long-term points deleted beyond the long-term cube

  Vec3 vc(const Vec3& p) const { return VoxelKey::fromPoint(p, visual_voxel).center(visual_voxel); }
  void apply(const HybridMap& map, const MapUpdateReport& rep) {
    if (rep.longterm_slid) {
      for (auto it = longterm.begin(); it != longterm.end();) {
        if (outside(vc(it->second.first), map.slides().longtermCenter(), lt_half)) {
          it = longterm.erase(it);
          ++lt_deleted;
        } else {
          ++it;
        }
      }
    }
    if (!rep.slid) return;
    const Vec3 c = map.slides().localCenter();
    for (auto it = roots.begin(); it != roots.end();) {
      const VoxelKey k{std::get<0>(*it), std::get<1>(*it), std::get<2>(*it)};
      it = outside(k.center(lidar_voxel), c, local_half) ? roots.erase(it) : std::next(it);
    }
    std::map<std::int64_t, std::pair<Vec3, bool>> back;
    for (auto it = longterm.begin(); it != longterm.end();) {
      if (outside(vc(it->second.first), c, local_half)) {
        ++it;
      } else {
        back.insert(*it);
        it = longterm.erase(it);
      }
    }
    for (auto it = local.begin(); it != local.end();) {
      if (!outside(vc(it->second.first), c, local_half)) {
        ++it;
        continue;
      }
      if (it->second.second && !outside(vc(it->second.first), map.slides().longtermCenter(), lt_half)) longterm.insert(*it);
      it = local.erase(it);
    }
    local.insert(back.begin(), back.end());
  }
  void expectMatches(const HybridMap& map) const {
    EXPECT_EQ(rootKeysWithPlanes(map.lidar().voxels()), roots);
    EXPECT_EQ(map.lidar().voxels().numRootVoxels(), roots.size());
    std::set<std::int64_t> want_local, want_lt;
    for (const auto& kv : local) want_local.insert(kv.first);
    for (const auto& kv : longterm) want_lt.insert(kv.first);
    EXPECT_EQ(ids(map.visual().local()), want_local);
    EXPECT_EQ(ids(map.visual().longterm()), want_lt);
  }
};

SlideModel modelOf(const Scene& sc) {
  SlideModel m;
  m.roots = sc.roots;
  m.local = sc.points;
  return m;
}

// Two maps of the same scene slid along the same short path (the long-term rules' comparisons).
void fillAndSlideBoth(HybridMap& a, HybridMap& b) {
  fillScene(a, 7);
  fillScene(b, 7);
  for (const Vec3& robot : {Vec3(0, 0, 0), Vec3(6, 1, 0), Vec3(13, -4, 0)}) {
    a.update(robot);
    b.update(robot);
  }
}

}  // namespace

TEST(HybridMap, SlideDeletesLocalVoxelsAndMovesVisualPointsToLongterm) {
  HybridMap map(smallConfig(), voxels1m(), VisualMapConfig{});
  const Scene sc = fillScene(map, 7);
  ASSERT_EQ(rootKeysWithPlanes(map.lidar().voxels()).size(), sc.roots.size()) << "every root must hold a plane";
  SlideModel model = modelOf(sc);
  for (const Vec3& robot : {Vec3(0, 0, 0), Vec3(3, 0, 0), Vec3(6, 1, 0), Vec3(13, -4, 0), Vec3(31, -4, 0)}) {
    const MapUpdateReport rep = map.update(robot);
    model.apply(map, rep);
    model.expectMatches(map);
    if (robot.x() == 3) {
      EXPECT_FALSE(rep.slid) << "3 m is below the slide distance";
    }
    if (robot.x() == 6) {
      EXPECT_TRUE(rep.slid);
    }
  }
  EXPECT_EQ(map.counters().slides, 4u);  // the first update centres the cube, then 6, 13 and 31 m
  EXPECT_GT(map.counters().moved_to_longterm, 1000u);
  EXPECT_GT(map.counters().deleted_points, 100u);  // points without a reference are not kept
  EXPECT_GT(map.counters().moved_to_local, 10u);   // the cube at x = 31 covers points that left at x = 13
  // Long-term points keep their reference patch only (fillScene: the last of 1 + id % 4).
  map.visual().longterm().forEach([](const VisualPoint& p) {
    EXPECT_EQ(p.reference, 0);
    EXPECT_EQ(p.obs[0].utime, p.id % 4);
    EXPECT_EQ(p.obs.size(), 1u);
    EXPECT_EQ(p.obs.capacity(), 1u);
    EXPECT_TRUE(p.from_longterm);
  });
  // The points it gave back keep the mark (the per-frame count of long-term points used reads it); fillScene's
  // points never left and have none.
  std::size_t returned = 0;
  map.visual().local().forEach([&returned](const VisualPoint& p) { returned += p.from_longterm; });
  EXPECT_GT(returned, 0u);
  EXPECT_LE(returned, map.counters().moved_to_local);
}

// map.longterm_enabled false: the same slides and LiDAR map, but every visual point that leaves the
// local cube is deleted, the long-term map stays empty and nothing comes back on a revisit.
TEST(HybridMap, WithoutLongtermMapLeavingPointsAreDeleted) {
  HybridMapConfig off_cfg = smallConfig();
  off_cfg.longterm_enabled = false;
  HybridMap with(smallConfig(), voxels1m(), VisualMapConfig{});
  HybridMap without(off_cfg, voxels1m(), VisualMapConfig{});
  const Scene sc = fillScene(with, 7);
  fillScene(without, 7);
  const std::size_t total = with.visual().local().size();
  ASSERT_EQ(without.visual().local().size(), total);
  for (const Vec3& robot : {Vec3(0, 0, 0), Vec3(6, 1, 0), Vec3(13, -4, 0)}) {
    with.update(robot);
    without.update(robot);
    EXPECT_EQ(without.visual().longterm().size(), 0u);
    // The same local map, except the points that the long-term map gave back on a revisit.
    const std::set<std::int64_t> a = ids(without.visual().local()), b = ids(with.visual().local());
    EXPECT_TRUE(std::includes(b.begin(), b.end(), a.begin(), a.end()));
    EXPECT_LE(b.size() - a.size(), with.counters().moved_to_local);  // returned ones may leave again
    EXPECT_EQ(rootKeysWithPlanes(without.lidar().voxels()), rootKeysWithPlanes(with.lidar().voxels()));
  }
  EXPECT_GT(with.counters().moved_to_longterm, 1000u);
  EXPECT_EQ(without.counters().moved_to_longterm, 0u);
  EXPECT_GT(with.counters().moved_to_local, 0u) << "the scene must have a revisit";
  EXPECT_EQ(without.counters().moved_to_local, 0u);
  without.visual().local().forEach([](const VisualPoint& p) { EXPECT_FALSE(p.from_longterm) << p.id; });
  EXPECT_EQ(without.counters().deleted_points, total - without.visual().local().size());
  EXPECT_LT(without.stats().bytes, with.stats().bytes);
}

// map.longterm_points_per_voxel: a point leaving the local cube into a full long-term voxel is deleted.
TEST(HybridMap, LongtermPointsPerVoxelCapsTheLongtermMap) {
  HybridMapConfig capped_cfg = smallConfig();
  capped_cfg.longterm_points_per_voxel = 1;
  HybridMap free_map(smallConfig(), voxels1m(), VisualMapConfig{});
  HybridMap capped(capped_cfg, voxels1m(), VisualMapConfig{});
  fillAndSlideBoth(free_map, capped);
  const VisualMap& lt = capped.visual().longterm();
  std::map<VoxelKey, int, bool (*)(const VoxelKey&, const VoxelKey&)> per_voxel(
      [](const VoxelKey& a, const VoxelKey& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); });
  lt.forEach([&](const VisualPoint& p) { ++per_voxel[lt.keyOf(p.p_world)]; });
  ASSERT_GT(per_voxel.size(), 10u);
  for (const auto& kv : per_voxel) EXPECT_EQ(kv.second, 1);
  EXPECT_EQ(lt.numVoxels(), per_voxel.size());
  // The uncapped map holds several points in some of these voxels: the cap did delete some.
  EXPECT_LT(lt.size(), free_map.visual().longterm().size());
  EXPECT_GT(capped.counters().deleted_points, free_map.counters().deleted_points);
}

// map.longterm_min_observations: a point leaving the local cube with fewer observations is deleted;
// the long-term map is the one without the rule less exactly those points (fillScene: 1 + id % 4
// observations per point).
TEST(HybridMap, LongtermMinObservationsKeepsOnlyPointsSeenOftenEnough) {
  HybridMapConfig strict_cfg = smallConfig();
  strict_cfg.longterm_min_observations = 3;
  HybridMap all(smallConfig(), voxels1m(), VisualMapConfig{});
  HybridMap strict(strict_cfg, voxels1m(), VisualMapConfig{});
  fillAndSlideBoth(all, strict);
  std::set<std::int64_t> want;
  for (std::int64_t id : ids(all.visual().longterm()))
    if (1 + id % 4 >= 3) want.insert(id);
  ASSERT_GT(want.size(), 100u);
  EXPECT_EQ(ids(strict.visual().longterm()), want);
  EXPECT_LT(strict.stats().bytes_visual_longterm, all.stats().bytes_visual_longterm);
  // Deleted instead: at least those (more where one returned to the local map and left again).
  EXPECT_GE(strict.counters().deleted_points - all.counters().deleted_points,
            all.visual().longterm().size() - want.size());
  // Bad values are refused, naming the key.
  HybridMapConfig bad = smallConfig();
  bad.longterm_min_observations = 0;
  try {
    bad.validate();
    ADD_FAILURE() << "longterm_min_observations 0 must be refused";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("longterm_min_observations"), std::string::npos) << e.what();
  }
}

TEST(HybridMap, SlideWorkIsSpreadOverUpdatesWithinTheBudget) {
  HybridMapConfig cfg = smallConfig();
  cfg.max_removals_per_update = 150;
  HybridMap budgeted(cfg, voxels1m(), VisualMapConfig{});
  HybridMap full(smallConfig(), voxels1m(), VisualMapConfig{});
  fillScene(budgeted, 11);
  fillScene(full, 11);
  full.update(Vec3(0, 0, 0));
  int updates = 0;
  MapUpdateReport rep = budgeted.update(Vec3(0, 0, 0));
  for (;; rep = budgeted.update(Vec3(0, 0, 0))) {
    ++updates;
    EXPECT_LE(rep.removed_voxels + rep.moved_to_longterm + rep.moved_to_local + rep.deleted_points, 150u);
    if (rep.pending == 0) break;
    ASSERT_LT(updates, 1000);
  }
  std::cout << "slide work over " << updates << " updates of at most 150 items\n";
  EXPECT_GT(updates, 10);
  EXPECT_EQ(rootKeysWithPlanes(budgeted.lidar().voxels()), rootKeysWithPlanes(full.lidar().voxels()));
  EXPECT_EQ(ids(budgeted.visual().local()), ids(full.visual().local()));
  EXPECT_EQ(ids(budgeted.visual().longterm()), ids(full.visual().longterm()));
}

TEST(HybridMap, LongtermDeletesBeyondItsEdgeAndRevisitsReturnPoints) {
  HybridMap map(smallConfig(), voxels1m(), VisualMapConfig{});
  const Scene sc = fillScene(map, 3);
  SlideModel model = modelOf(sc);
  // 45 m along +x in 1 m steps (the long-term cube, half edge 50, follows every 10 m), then back.
  for (int step = 0; step <= 90; ++step) {
    const int x = step <= 45 ? step : 90 - step;
    const MapUpdateReport rep = map.update(Vec3(x, 0, 0));
    model.apply(map, rep);
    model.expectMatches(map);
  }
  EXPECT_GT(model.lt_deleted, 100u);
  EXPECT_GE(map.counters().longterm_slides, 9u);
  EXPECT_GT(map.counters().moved_to_local, 100u);
  std::cout << "long-term: " << map.counters().moved_to_longterm << " moved in, " << map.counters().moved_to_local
            << " back, " << map.counters().deleted_points << " deleted\n";
}

TEST(HybridMap, MemoryCapEvictsFarthestLongtermPointsFirst) {
  HybridMap map(smallConfig(), voxels1m(), VisualMapConfig{});
  fillScene(map, 5);
  const Vec3 robot(10, 0, 0);
  map.update(Vec3(0, 0, 0));
  map.update(robot);
  const HybridMapStats before = map.stats();
  ASSERT_GT(before.visual_points_longterm, 500u);
  std::map<std::int64_t, double> lt_dist;
  map.visual().longterm().forEach([&](const VisualPoint& p) { lt_dist[p.id] = (p.p_world - robot).norm(); });
  // A cap that part of the long-term map must make room for.
  const double cap_mb = double(before.bytes - before.bytes_visual_longterm / 2) / (1024.0 * 1024.0);
  map.setMemoryCapMb(cap_mb);
  const MapUpdateReport rep = map.update(robot);
  const HybridMapStats after = map.stats();
  EXPECT_LE(after.bytes, after.cap_bytes);
  EXPECT_TRUE(rep.recounted);
  EXPECT_NEAR(double(rep.bytes), double(after.bytes), 0.02 * double(after.bytes)) << "estimate after an eviction";
  EXPECT_GT(rep.evicted_longterm_points, 0u);
  EXPECT_LT(after.visual_points_longterm, before.visual_points_longterm);
  EXPECT_EQ(rep.evicted_local_voxels, 0u) << "the long-term points are evicted first";
  EXPECT_EQ(rep.evicted_local_points, 0u);
  EXPECT_EQ(after.local_voxels, before.local_voxels);
  // Farthest first: every kept long-term point is at most as far from the robot as every evicted one.
  double max_kept = 0.0, min_evicted = 1e300;
  for (const auto& [id, d] : lt_dist) {
    if (map.visual().longterm().find(id)) max_kept = std::max(max_kept, d);
    else min_evicted = std::min(min_evicted, d);
  }
  EXPECT_LE(max_kept, min_evicted);
  EXPECT_EQ(map.counters().eviction_events, 1u);
  // Hysteresis: the next updates (nothing new) do not evict again.
  for (int i = 0; i < 3; ++i) EXPECT_EQ(map.update(robot).evicted_longterm_points, 0u);
  EXPECT_EQ(map.counters().eviction_events, 1u);
}

TEST(HybridMap, MemoryCapEvictsFarthestLocalContentWhenLongtermIsGone) {
  HybridMapConfig cfg = smallConfig();
  cfg.memory_cap_mb = 1.0;
  HybridMap map(cfg, voxels1m(), VisualMapConfig{});
  const Scene sc = fillScene(map, 9);
  const Vec3 robot(2, 1, 0);
  const MapUpdateReport rep = map.update(robot);
  const HybridMapStats s = map.stats();
  std::cout << "cap " << cfg.capBytes() << " B: " << s.bytes << " B after evicting " << rep.evicted_longterm_points
            << " long-term points, " << rep.evicted_local_voxels << " voxels, " << rep.evicted_local_points
            << " local points\n";
  EXPECT_LE(s.bytes, cfg.capBytes());
  EXPECT_GE(double(s.bytes), 0.7 * double(cfg.capBytes())) << "evicts down to the low-water mark, not far below";
  EXPECT_EQ(s.visual_points_longterm, 0u);
  EXPECT_GT(rep.evicted_local_voxels, 0u);
  // Farthest first over voxels (centres) and local points (positions) together.
  const std::set<KeyT> kept = rootKeysWithPlanes(map.lidar().voxels());
  double max_kept = 0.0, min_evicted = 1e300;
  for (const KeyT& k : sc.roots) {
    const VoxelKey key{std::get<0>(k), std::get<1>(k), std::get<2>(k)};
    const Vec3 c = key.center(1.0);
    if (outside(c, map.slides().localCenter(), 20.0)) continue;  // removed by the slide, not the cap
    const double d = (c - robot).norm();
    if (kept.count(k)) max_kept = std::max(max_kept, d);
    else min_evicted = std::min(min_evicted, d);
  }
  // Local points: kept ones count as kept, those inside the cube that are gone were evicted.
  const double vs = map.visual().local().config().voxel_size_m;
  for (const auto& [id, pr] : sc.points) {
    if (outside(VoxelKey::fromPoint(pr.first, vs).center(vs), map.slides().localCenter(), 20.0)) continue;
    const double d = (pr.first - robot).norm();
    if (map.visual().local().find(id)) max_kept = std::max(max_kept, d);
    else min_evicted = std::min(min_evicted, d);
  }
  EXPECT_LE(max_kept, min_evicted + 1e-9);
  // Later updates keep the bytes under the cap.
  for (int i = 0; i < 5; ++i) {
    const MapUpdateReport r = map.update(robot);
    EXPECT_LE(r.bytes, cfg.capBytes());
  }
}

TEST(HybridMap, EvictionIsSpreadOverUpdatesWithinTheBudgetBelowTheCap) {
  HybridMapConfig cfg = smallConfig();
  cfg.max_removals_per_update = 50;
  HybridMap map(cfg, voxels1m(), VisualMapConfig{});
  fillScene(map, 9);
  const Vec3 robot(2, 1, 0);
  for (MapUpdateReport r = map.update(robot); r.pending > 0; r = map.update(robot)) {
  }
  const std::size_t b = map.stats().bytes;
  const auto items = [](const MapUpdateReport& r) {
    return r.removed_voxels + r.moved_to_longterm + r.moved_to_local + r.deleted_points + r.evicted_longterm_points +
           r.evicted_local_voxels + r.evicted_local_points;
  };
  // Between the high-water mark and the cap: the eviction goes at the budget's pace.
  map.setMemoryCapMb(double(b) / 0.97 / 1048576.0);
  int updates = 0;
  for (MapUpdateReport r = map.update(robot);; r = map.update(robot)) {
    ++updates;
    EXPECT_LE(items(r), 50u);
    EXPECT_LE(r.bytes, map.stats().cap_bytes);
    if (r.pending == 0) break;
    ASSERT_LT(updates, 1000);
  }
  EXPECT_GT(updates, 3);
  EXPECT_EQ(map.counters().eviction_events, 1u);
  EXPECT_LE(map.stats().bytes, map.stats().cap_bytes);
  // Over the cap itself: evicted beyond the budget within one update.
  map.setMemoryCapMb(double(b) / 2.0 / 1048576.0);
  const MapUpdateReport r = map.update(robot);
  EXPECT_GT(items(r), 50u);
  EXPECT_LE(r.bytes, map.stats().cap_bytes);
  EXPECT_LE(map.stats().bytes, map.stats().cap_bytes);
}

TEST(HybridMap, GlobalModeNeverSlidesNorEvicts) {
  HybridMapConfig cfg = smallConfig();
  cfg.mode = MapMode::Global;
  cfg.memory_cap_mb = 0.1;
  HybridMap map(cfg, voxels1m(), VisualMapConfig{});
  const Scene sc = fillScene(map, 1);
  for (int x = 0; x <= 200; x += 10) {
    const MapUpdateReport rep = map.update(Vec3(x, 0, 0));
    EXPECT_FALSE(rep.slid);
    EXPECT_EQ(rep.removed_voxels + rep.evicted_local_voxels + rep.evicted_longterm_points, 0u);
  }
  EXPECT_EQ(map.lidar().voxels().numRootVoxels(), sc.roots.size());
  EXPECT_EQ(map.visual().local().size(), sc.points.size());
  EXPECT_EQ(map.visual().longterm().size(), 0u);
  EXPECT_EQ(map.counters().slides + map.counters().eviction_events, 0u);
  EXPECT_GT(map.stats().bytes, cfg.capBytes()) << "the cap does not apply in global mode";
  EXPECT_EQ(map.stats().cap_bytes, 0u);
}

TEST(HybridMap, RetrievalSearchesBothVisualMaps) {
  CameraConfig cc;
  cc.enabled = true;
  cc.model = CameraKind::Pinhole;
  cc.width = 640;
  cc.height = 480;
  cc.fx = cc.fy = 400.0;
  cc.cx = 319.5;
  cc.cy = 239.5;
  const auto cam = CameraModel::create(cc);
  HybridMap map(smallConfig(), voxels1m(), VisualMapConfig{});
  // Camera at the origin looking along +x (camera z = world x, camera x = -world y, camera y = -world z).
  Mat3 R_wc;
  R_wc << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Pose T_wc = Pose::Identity();
  T_wc.linear() = R_wc;
  const ImageGrid grid = selectionGrid(*cam, map.visual().local().config().grid_cell_px);
  map.update(Vec3(0, 0, 0));
  // One point per grid cell centre (cells 30 px apart: no occlusion between them), depth 4 m (stays
  // local) or 30 m (moves to the long-term map when the cube slides to x = -15).
  std::vector<Vec3> scan;
  std::map<int, std::int64_t> cell_id;
  std::int64_t id = 1;
  for (int r = 2; r < grid.rows - 2; ++r)
    for (int c = 2; c < grid.cols - 2; ++c, ++id) {
      const double z = (r + c) % 2 == 0 ? 4.0 : 30.0;
      const Vec2 px((c + 0.5) * grid.cell_px, (r + 0.5) * grid.cell_px);
      const Vec3 p = T_wc * Vec3((px.x() - cc.cx) / cc.fx * z, (px.y() - cc.cy) / cc.fy * z, z);
      ASSERT_TRUE(map.visual().local().insert(visualPoint(id, p)));
      scan.push_back(p);
      cell_id[grid.cellOf(px)] = id;
    }
  map.update(Vec3(-15, 0, 0));  // cube [-35, 5] in x
  ASSERT_GT(map.visual().longterm().size(), 50u);
  ASSERT_GT(map.visual().local().size(), 50u);
  const VisualRetrieval r = map.visual().retrieve(*cam, T_wc, scan);
  const std::vector<VisualPoint*>& got = r.points;
  const std::vector<Vec2>& pixels = r.pixels;
  ASSERT_EQ(got.size(), cell_id.size());
  ASSERT_EQ(pixels.size(), got.size());
  std::size_t k = 0, from_lt = 0;
  for (const auto& [cell, want] : cell_id) {  // ordered by cell
    EXPECT_EQ(got[k]->id, want);
    EXPECT_EQ(grid.cellOf(pixels[k]), cell);
    EXPECT_TRUE(r.occupied[std::size_t(cell)]);
    from_lt += map.visual().isLongterm(*got[k]);
    ++k;
  }
  EXPECT_EQ(from_lt, map.visual().longterm().size());
  EXPECT_EQ(r.longterm, from_lt);
  EXPECT_EQ(r.stats.selected, got.size());
  EXPECT_EQ(std::count(r.occupied.begin(), r.occupied.end(), true), long(got.size()));
  // Per cell, the nearer of the two maps' winners: add a local point at depth 3 m next to a
  // long-term winner (12 px away), then it wins that cell.
  const VisualPoint* lt_point = nullptr;
  for (VisualPoint* p : got)
    if (map.visual().isLongterm(*p)) lt_point = p;
  ASSERT_NE(lt_point, nullptr);
  Vec2 lt_px;
  ASSERT_TRUE(cam->project(T_wc.inverse() * lt_point->p_world, lt_px));
  const Vec2 near_px = lt_px + Vec2(12, 0);
  const Vec3 near = T_wc * Vec3((near_px.x() - cc.cx) / cc.fx * 3.0, (near_px.y() - cc.cy) / cc.fy * 3.0, 3.0);
  ASSERT_TRUE(map.visual().local().insert(visualPoint(100000, near)));
  scan.push_back(near);
  const std::int64_t lt_id = lt_point->id;
  const std::vector<VisualPoint*> got2 = map.visual().retrieve(*cam, T_wc, scan).points;
  ASSERT_EQ(got2.size(), got.size());
  bool found_near = false, found_lt = false;
  for (VisualPoint* p : got2) {
    found_near |= p->id == 100000;
    found_lt |= p->id == lt_id;
  }
  EXPECT_TRUE(found_near);
  EXPECT_FALSE(found_lt);
  // Photometric outliers are removed from the map that holds them.
  VisualPoint* victim = nullptr;
  for (VisualPoint* p : got2)
    if (map.visual().isLongterm(*p)) victim = p;
  ASSERT_NE(victim, nullptr);
  const std::int64_t victim_id = victim->id;
  Image gray;  // a flat image: observe() reports the error whether or not it adds the observation
  gray.width = cc.width;
  gray.height = cc.height;
  gray.row_stride = cc.width;
  gray.data.assign(std::size_t(cc.width) * std::size_t(cc.height), 128);
  Vec2 victim_px;
  ASSERT_TRUE(cam->project(T_wc.inverse() * victim->p_world, victim_px));
  const std::size_t local_before = map.visual().local().size();
  for (int i = 0; i <= map.visual().local().config().max_bad_updates; ++i)
    map.visual().observe(*victim, 1e6, 1.0, gray, T_wc, victim_px, 1.f, Utime(i + 1), nullptr);
  EXPECT_EQ(map.visual().removeBadPoints(), 1u);
  EXPECT_EQ(map.visual().local().size(), local_before);
  EXPECT_EQ(map.visual().longterm().find(victim_id), nullptr);
}

TEST(HybridMap, ByteAccountingIsTheSumOfTheParts) {
  HybridMapConfig cfg = smallConfig();
  cfg.memory_cap_mb = 1000.0;  // never reached; makes update() count exactly
  cfg.recount_interval = 1;
  HybridMap map(cfg, voxels1m(), VisualMapConfig{});
  fillScene(map, 2);
  map.update(Vec3(10, 0, 0));
  const MapUpdateReport rep = map.update(Vec3(10, 0, 0));  // no work left: counts after nothing changed
  ASSERT_TRUE(rep.recounted);
  const HybridMapStats s = map.stats();
  EXPECT_EQ(s.bytes_lidar, map.lidar().voxels().bytes());
  EXPECT_EQ(s.bytes_visual_local, map.visual().local().bytes() + map.visual().local().scratchBytes());
  EXPECT_EQ(s.bytes_visual_longterm, map.visual().longterm().bytes() + map.visual().longterm().scratchBytes());
  EXPECT_EQ(s.bytes, s.bytes_lidar + s.bytes_visual_local + s.bytes_visual_longterm + s.bytes_index);
  EXPECT_EQ(s.bytes, map.bytes());
  EXPECT_GT(s.bytes_index, 0u);
  EXPECT_LT(s.bytes_index, s.bytes_lidar / 5) << "the tile index is small next to the map";
  EXPECT_EQ(rep.bytes, s.bytes);
  // Right after an exact count the O(1) estimate equals it (up to rounding).
  EXPECT_NEAR(double(map.bytesEstimate()), double(s.bytes), 8.0);
  std::cout << "bytes: lidar " << s.bytes_lidar << " (" << double(s.bytes_lidar) / double(s.local_voxels)
            << " per root voxel), visual local " << s.bytes_visual_local << ", long-term " << s.bytes_visual_longterm
            << ", index " << s.bytes_index << "\n";
}

// The map server's upsert of an estimator's copy: a rejected copy leaves the stored point in place,
// and a copy made before the point moved to the long-term map does not clear its long-term mark.
TEST(HybridMap, UpsertKeepsTheStoredPointOnRejectionAndTheLongtermMark) {
  DualVisualMap dual{VisualMapConfig{}};
  auto lt = visualPoint(7, Vec3(2, 0, 1));
  lt->from_longterm = true;
  ASSERT_TRUE(dual.longterm().insert(std::move(lt)));
  VisualPoint copy = *visualPoint(7, Vec3(2, 0, 1), true, 2);  // the estimator's copy: no mark yet
  VisualPoint bad = copy;
  bad.p_world.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(dual.upsert(bad));
  ASSERT_NE(dual.longterm().find(7), nullptr) << "a rejected copy must not remove the point";
  EXPECT_EQ(dual.longterm().find(7)->obs.size(), 1u);
  bad = copy;
  bad.reference = 5;
  EXPECT_FALSE(dual.upsert(bad));
  ASSERT_NE(dual.longterm().find(7), nullptr);
  EXPECT_TRUE(dual.upsert(copy));
  const VisualPoint* p = dual.longterm().find(7);
  ASSERT_NE(p, nullptr) << "the copy replaces the point in the map that holds it";
  EXPECT_EQ(p->obs.size(), 2u);
  EXPECT_TRUE(p->from_longterm);
  EXPECT_TRUE(dual.isLongterm(*p));
  // A removal (no observations) still removes it.
  VisualPoint removal;
  removal.id = 7;
  EXPECT_TRUE(dual.upsert(removal));
  EXPECT_EQ(dual.longterm().find(7), nullptr);
}
