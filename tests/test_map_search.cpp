// libs/map: nearest-plane search against brute force over every plane (negative coordinates, voxel
// borders, neighbour voxel from the metric position), concurrent const queries, removal.
#include "map_test_util.hpp"

#include "livo/map/plane.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/map/voxel_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <thread>
#include <vector>

using namespace livo;
using namespace livo::test;

// ---------------------------------------------------------------- nearest-plane search
namespace {

// Oracle: the acceptance criteria of docs/algorithms.md section 2 evaluated over EVERY plane of the map,
// restricted by key comparison to the point's root voxel, then to the one neighbour voxel chosen from
// the metric position inside the voxel (outer quarters).
class BruteForceSearch {
 public:
  explicit BruteForceSearch(const VoxelMap& map) : s_(map.config().voxel_size_m), k_(map.config().sigma_num) {
    map.forEachPlane([this](const VoxelKey& key, const Plane& p) { planes_.push_back({key, &p}); });
  }
  bool find(const PointWithCov& pw, VoxelMap::PlaneMatch& out) const {
    const Vec3& p = pw.p_world;
    const VoxelKey own{(std::int64_t)std::floor(p.x() / s_), (std::int64_t)std::floor(p.y() / s_),
                       (std::int64_t)std::floor(p.z() / s_)};
    if (bestIn(own, pw, out)) return true;
    VoxelKey near = own;
    bool step = false;
    std::int64_t* k[3] = {&near.x, &near.y, &near.z};
    const std::int64_t o[3] = {own.x, own.y, own.z};
    for (int i = 0; i < 3; ++i) {
      const double local = p[i] - static_cast<double>(o[i]) * s_;  // metres inside the voxel
      if (local > 0.75 * s_) {
        *k[i] += 1;
        step = true;
      } else if (local < 0.25 * s_) {
        *k[i] -= 1;
        step = true;
      }
    }
    return step && bestIn(near, pw, out);
  }
  std::size_t size() const { return planes_.size(); }
  const std::vector<std::pair<VoxelKey, const Plane*>>& planes() const { return planes_; }

 private:
  bool bestIn(const VoxelKey& key, const PointWithCov& pw, VoxelMap::PlaneMatch& out) const {
    out = VoxelMap::PlaneMatch{};
    for (const auto& kp : planes_) {
      if (kp.first != key) continue;
      const Plane& pl = *kp.second;
      const Vec3 e = pw.p_world - pl.center;
      const double d = pl.normal.dot(e);
      if (std::sqrt(std::max(e.squaredNorm() - d * d, 0.0)) > k_ * pl.radius) continue;
      Vec6 J;
      J << e, -pl.normal;
      const double sigma_l = (J.transpose() * pl.cov_nq * J)(0, 0) + pl.normal.transpose() * pw.cov_world * pl.normal;
      if (!(std::abs(d) < k_ * std::sqrt(sigma_l))) continue;
      const double prob = std::exp(-d * d / (2 * sigma_l)) / std::sqrt(sigma_l);
      if (out.plane && prob <= out.probability) continue;
      out = VoxelMap::PlaneMatch{&pl, d, sigma_l, prob};
    }
    return out.plane != nullptr;
  }
  double s_, k_;
  std::vector<std::pair<VoxelKey, const Plane*>> planes_;
};

struct Scene {
  std::vector<PointWithCov> points;
  std::vector<PointWithCov> queries;
};

// Random planes through [-2, 2]^3 plus two planes lying exactly on voxel borders (x = -1, z = 0);
// queries near the planes, a third of them with coordinates snapped onto voxel borders, just next to
// them, or onto the quarter lines that decide the neighbour voxel.
Scene makeScene(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  const Vec3 sensor(0.3, -0.2, 0.1);
  std::vector<std::pair<Vec3, Vec3>> planes;  // (point, normal)
  for (int i = 0; i < 6; ++i) planes.push_back({2.0 * Vec3(u(rng), u(rng), u(rng)), randomUnit(rng)});
  planes.push_back({Vec3(-1.0, 0, 0), Vec3::UnitX()});
  planes.push_back({Vec3(0, 0, 0.0), Vec3::UnitZ()});
  Scene sc;
  std::vector<Vec3> clean;
  for (std::size_t j = 0; j < planes.size(); ++j) {
    Vec3 t1, t2;
    tangentBasis(planes[j].second, t1, t2);
    for (int i = 0; i < 2500; ++i) {
      Vec3 p = planes[j].first + 2.0 * u(rng) * t1 + 2.0 * u(rng) * t2;
      if (j >= 6) p[j == 6 ? 0 : 2] = planes[j].first[j == 6 ? 0 : 2];  // exactly on the border
      if (p.cwiseAbs().maxCoeff() > 2.5) continue;
      clean.push_back(p);
      PointWithCov pw = withCov(p, sensor, 0.01, 0.05);
      if (!(j >= 6 && i % 2 == 0)) pw.p_world = sampleGaussian(p, pw.cov_world, rng);  // half exact
      sc.points.push_back(pw);
    }
  }
  std::shuffle(sc.points.begin(), sc.points.end(), rng);
  const double s = 0.5;
  for (int i = 0; i < 4000; ++i) {
    Vec3 p = clean[rng() % clean.size()] + 0.03 * n01(rng) * randomUnit(rng);
    if (i % 3 == 0) {
      const int axis = rng() % 3;
      const double base = std::floor(p[axis] / s) * s;
      const double choices[] = {base, base + s, std::nextafter(base, -1e9), std::nextafter(base, 1e9),
                                base + 0.25 * s, base + 0.75 * s};
      p[axis] = choices[rng() % 6];
    }
    sc.queries.push_back(withCov(p, sensor, 0.01, 0.05));
  }
  return sc;
}

}  // namespace

TEST(Search, MatchesBruteForceOverAllPlanes) {
  for (unsigned seed : {21u, 22u, 23u}) {
    const Scene sc = makeScene(seed);
    VoxelMap map;
    // Two batches: the second one updates existing voxels incrementally.
    const std::size_t half = sc.points.size() / 2;
    map.insert({sc.points.begin(), sc.points.begin() + half});
    map.insert({sc.points.begin() + half, sc.points.end()});
    const BruteForceSearch oracle(map);
    ASSERT_GT(oracle.size(), 100u);
    // Every plane lies inside the root voxel of its key (floor keys, also for negative coordinates).
    for (const auto& kp : oracle.planes()) {
      const Vec3 lo = Vec3(kp.first.x, kp.first.y, kp.first.z) * 0.5;
      EXPECT_TRUE((kp.second->center.array() >= lo.array() - 1e-12).all() &&
                  (kp.second->center.array() <= lo.array() + 0.5 + 1e-12).all());
    }
    int matched = 0, via_neighbour = 0, negative = 0;
    for (const PointWithCov& q : sc.queries) {
      VoxelMap::PlaneMatch got, want;
      const bool ok = map.findBestPlane(q, got);
      ASSERT_EQ(ok, oracle.find(q, want)) << q.p_world.transpose();
      if (!ok) continue;
      ++matched;
      if (map.keyOf(q.p_world) != map.keyOf(want.plane->center)) ++via_neighbour;
      if ((q.p_world.array() < 0).any()) ++negative;
      EXPECT_EQ(got.plane, want.plane);
      EXPECT_NEAR(got.distance, want.distance, 1e-12);
      EXPECT_NEAR(got.sigma_l / want.sigma_l, 1.0, 1e-9);
      EXPECT_NEAR(got.probability / want.probability, 1.0, 1e-9);
    }
    // The scene exercises what it should.
    EXPECT_GT(matched, 2000) << "seed " << seed;
    EXPECT_GT(via_neighbour, 20) << "seed " << seed;
    EXPECT_GT(negative, 1000) << "seed " << seed;
  }
}

TEST(Search, NeighbourVoxelFromMetricPosition) {
  // One horizontal plane filling root voxel (-1, 0, 0), i.e. x in [-0.5, 0).
  VoxelMap map;
  std::vector<PointWithCov> pts;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 5; ++j) pts.push_back(withCov(Vec3(-0.49 + 0.05 * i, 0.05 + 0.1 * j, 0.25), Vec3(0, 0, 2)));
  map.insert(pts);
  ASSERT_EQ(map.numPlanes(), 1u);
  VoxelMap::PlaneMatch m;
  auto at = [&](double x, double y) { return withCov(Vec3(x, y, 0.25), Vec3(0, 0, 2)); };
  EXPECT_TRUE(map.findBestPlane(at(-0.2, 0.3), m));   // own voxel
  EXPECT_TRUE(map.findBestPlane(at(0.05, 0.3), m));   // voxel 0, lower quarter -> step -1 in x
  EXPECT_FALSE(map.findBestPlane(at(0.2, 0.3), m));   // voxel 0, middle: no neighbour tried
  EXPECT_TRUE(map.findBestPlane(at(-0.55, 0.3), m));  // voxel -2, upper quarter -> step +1 in x
  EXPECT_FALSE(map.findBestPlane(at(-0.7, 0.3), m));
  EXPECT_FALSE(map.findBestPlane(at(0.05, 0.45), m)); // corner: the diagonal neighbour (-1, 1) is empty
  VoxelKey k;
  EXPECT_TRUE(map.neighbourKey(Vec3(0.05, 0.45, 0.25), k));
  EXPECT_EQ(k, (VoxelKey{-1, 1, 0}));
  EXPECT_FALSE(map.neighbourKey(Vec3(0.125, 0.375, 0.25), k));  // exactly on the quarter lines
}

TEST(Search, ConcurrentConstQueriesMatchSerial) {
  const Scene sc = makeScene(31);
  VoxelMap map;
  map.insert(sc.points);
  std::vector<VoxelMap::PlaneMatch> serial(sc.queries.size()), parallel(sc.queries.size());
  for (std::size_t i = 0; i < sc.queries.size(); ++i) map.findBestPlane(sc.queries[i], serial[i]);
  auto work = [&](std::size_t begin, std::size_t step) {
    for (std::size_t i = begin; i < sc.queries.size(); i += step) map.findBestPlane(sc.queries[i], parallel[i]);
  };
  std::thread a(work, 0, 2), b(work, 1, 2);
  a.join();
  b.join();
  for (std::size_t i = 0; i < serial.size(); ++i) {
    EXPECT_EQ(serial[i].plane, parallel[i].plane);
    EXPECT_EQ(serial[i].probability, parallel[i].probability);
  }
}

TEST(Search, RemoveOutsideBoxAndSingleVoxels) {
  const Scene sc = makeScene(41);
  VoxelMap map;
  map.insert(sc.points);
  const std::size_t before = map.numRootVoxels();
  const Vec3 c(0.3, -0.4, 0.1);
  const std::size_t removed = map.removeOutsideBox(c, 1.0);
  EXPECT_GT(removed, 0u);
  EXPECT_EQ(map.numRootVoxels(), before - removed);
  map.forEachPlane([&](const VoxelKey& k, const Plane&) {
    EXPECT_LE((k.center(0.5) - c).cwiseAbs().maxCoeff(), 1.0);
  });
  VoxelKey some{};
  map.forEachPlane([&](const VoxelKey& k, const Plane&) { some = k; });
  EXPECT_EQ(map.removeVoxel(some), 1u);
  EXPECT_EQ(map.removeVoxel(some), 0u);
  EXPECT_EQ(map.numRootVoxels(), before - removed - 1);
  // The search still agrees with the oracle on what is left.
  const BruteForceSearch oracle(map);
  for (const PointWithCov& q : sc.queries) {
    VoxelMap::PlaneMatch got, want;
    ASSERT_EQ(map.findBestPlane(q, got), oracle.find(q, want));
    EXPECT_EQ(got.plane, want.plane);
  }
}

// The LiDAR update keeps each point's candidate planes across its iterations (CachedAssociation):
// along a walk of small steps (most stay in their voxel, some cross a border or a quarter line that
// changes the neighbour) its answer is findBestPlane's, plane and numbers, every step.
TEST(Search, CachedAssociationEqualsFindBestPlaneAlongAWalk) {
  const Scene sc = makeScene(41);
  VoxelMap map;
  map.insert(sc.points);
  std::mt19937 rng(42);
  std::normal_distribution<double> step(0.0, 0.02);
  int steps = 0, matched = 0, cached_hits = 0;
  for (std::size_t i = 0; i < sc.queries.size(); i += 4) {
    CachedAssociation cache;
    PointWithCov q = sc.queries[i];
    VoxelKey last_key = map.keyOf(q.p_world);
    for (int k = 0; k < 6; ++k) {
      VoxelMap::PlaneMatch want, got;
      const bool ok = map.findBestPlane(q, want);
      ASSERT_EQ(cache.find(map, q, got), ok) << q.p_world.transpose() << " step " << k;
      ++steps;
      cached_hits += k > 0 && map.keyOf(q.p_world) == last_key;
      last_key = map.keyOf(q.p_world);
      if (ok) {
        ++matched;
        EXPECT_EQ(got.plane, want.plane);
        EXPECT_EQ(got.distance, want.distance);
        EXPECT_EQ(got.sigma_l, want.sigma_l);
        EXPECT_EQ(got.probability, want.probability);
      }
      q.p_world += Vec3(step(rng), step(rng), step(rng));
      q.cov_world *= 0.8;  // gates shrink as in the iterations
    }
  }
  EXPECT_GT(matched, steps / 3);
  EXPECT_GT(cached_hits, steps / 2) << "most steps stay in their voxel (the cache is used)";
  EXPECT_LT(cached_hits, steps * 5 / 6) << "some steps leave it (the cache is refreshed)";
  // Non-finite points: no match, as findBestPlane.
  CachedAssociation cache;
  PointWithCov bad = sc.queries[0];
  bad.p_world.x() = std::nan("");
  VoxelMap::PlaneMatch m;
  EXPECT_FALSE(cache.find(map, bad, m));
}
