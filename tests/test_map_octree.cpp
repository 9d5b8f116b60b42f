// libs/map: voxel keys of negative coordinates, map config loading and errors, and octree behaviour
// (plane at layer 0 refitted every six points, split at a corner, freezing at the point limit).
#include "map_test_util.hpp"

#include "livo/common/config.hpp"
#include "livo/map/plane.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/map/voxel_map.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace livo;
using namespace livo::test;

// ---------------------------------------------------------------- keys and config
TEST(VoxelKeyTest, FloorForNegativeCoordinates) {
  const double s = 0.5;
  EXPECT_EQ(VoxelKey::fromPoint(Vec3(-0.1, 0.1, 0.0), s), (VoxelKey{-1, 0, 0}));
  EXPECT_EQ(VoxelKey::fromPoint(Vec3(-0.5, 0.5, 0.4999), s), (VoxelKey{-1, 1, 0}));
  EXPECT_EQ(VoxelKey::fromPoint(Vec3(-0.5000001, -1e-300, -1.0), s), (VoxelKey{-2, -1, -2}));
  EXPECT_EQ(VoxelKey::fromPoint(Vec3(-0.1, -0.1, -0.1), 0.2), (VoxelKey{-1, -1, -1}));
  EXPECT_TRUE((VoxelKey{-1, 0, 3}).center(s).isApprox(Vec3(-0.25, 0.25, 1.75)));
  // Distinct keys of a 20^3 block around the origin get distinct hashes.
  std::vector<std::size_t> hashes;
  for (int x = -10; x < 10; ++x)
    for (int y = -10; y < 10; ++y)
      for (int z = -10; z < 10; ++z) hashes.push_back(VoxelKeyHash()(VoxelKey{x, y, z}));
  std::sort(hashes.begin(), hashes.end());
  EXPECT_EQ(std::unique(hashes.begin(), hashes.end()) - hashes.begin(), 8000);
}

TEST(VoxelMapConfigTest, LoadsAndNamesBadKeys) {
  auto f = ConfigFile::parse(
      "lio:\n  voxel_size_m: 0.4\n  max_layer: 1\n  layer_init_num: [4, 6]\n  max_points: 100\n"
      "  min_eigen_value: 1.0e-4\n  sigma_num: 2.5\n",
      "rig.yaml");
  VoxelMapConfig c;
  c.load(f.root().section("lio"));
  EXPECT_EQ(c.voxel_size_m, 0.4);
  EXPECT_EQ(c.max_layer, 1);
  EXPECT_EQ(c.initNum(1), 6);
  EXPECT_EQ(c.max_points, 100);
  EXPECT_EQ(c.min_eigen_value, 1e-4);
  EXPECT_EQ(c.sigma_num, 2.5);
  f.checkAllKeysUsed();
  for (const char* bad : {"voxel_size_m: -1", "max_layer: 3\n  layer_init_num: [5, 5]", "max_points: 4",
                          "min_eigen_value: 0", "sigma_num: 0"}) {
    const std::string yaml = std::string("lio:\n  ") + bad + "\n";
    const std::string key = std::string(bad).substr(0, std::string(bad).find(':'));
    const std::string expect = key == "max_layer" ? "layer_init_num" : key;
    VoxelMapConfig d;
    try {
      d.load(ConfigFile::parse(yaml, "rig.yaml").root().section("lio"));
      ADD_FAILURE() << "accepted " << bad;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("lio." + expect), std::string::npos) << e.what();
    }
  }
}

// ---------------------------------------------------------------- octree
TEST(Octree, PlanarPatchBecomesPlaneAtLayer0AndRefitsEverySixPoints) {
  VoxelMap map;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.01, 0.49);
  auto patch = [&](int n) {
    std::vector<PointWithCov> v;
    for (int i = 0; i < n; ++i) v.push_back(withCov(Vec3(-u(rng), u(rng), -0.3), Vec3(0, 0, 1)));
    return v;
  };
  map.insert(patch(5));
  EXPECT_EQ(map.numPlanes(), 0u);  // needs more than layer_init_num = 5
  map.insert(patch(1));
  ASSERT_EQ(map.numPlanes(), 1u);
  std::vector<Plane> planes;
  map.forEachPlane([&](const VoxelKey& k, const Plane& p) {
    EXPECT_EQ(k, (VoxelKey{-1, 0, -1}));
    planes.push_back(p);
  });
  EXPECT_EQ(planes[0].layer, 0);
  EXPECT_EQ(planes[0].num_points, 6);
  EXPECT_GT(std::abs(planes[0].normal.z()), 0.999);
  auto numPointsOfPlane = [&] {
    int n = -1;
    map.forEachPlane([&](const VoxelKey&, const Plane& p) { n = p.num_points; });
    return n;
  };
  map.insert(patch(5));
  EXPECT_EQ(numPointsOfPlane(), 6);  // 5 new points: no refit yet
  map.insert(patch(1));
  EXPECT_EQ(numPointsOfPlane(), 12);
  EXPECT_EQ(map.numRootVoxels(), 1u);
}

TEST(Octree, CornerSplitsIntoPlanarChildren) {
  // Hilti's planarity threshold: with 0.0025 m^2 the L-shaped corner cells (0.15 m legs) would
  // themselves count as planar.
  VoxelMapConfig cfg;
  cfg.min_eigen_value = 1e-4;
  VoxelMap map(cfg);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.001);
  std::vector<PointWithCov> pts;
  for (int i = 0; i < 1200; ++i) {  // floor z = 0.1 (x < 0.4) and wall x = 0.4 (z > 0.1) of voxel 0
    const Vec3 p = (i % 2 == 0) ? Vec3(0.4 * u(rng), 0.5 * u(rng), 0.1 + noise(rng))
                                : Vec3(0.4 + noise(rng), 0.5 * u(rng), 0.1 + 0.4 * u(rng));
    pts.push_back(withCov(p, Vec3(0.2, 0.25, 1.0), 0.001, 0.05));
  }
  map.insert(pts);
  int at_layer[3] = {0, 0, 0};
  map.forEachPlane([&](const VoxelKey&, const Plane& p) {
    ++at_layer[p.layer];
    // Layers 0-1 hold only the floor or only the wall. (A 0.125 m cell has at most 0.125^2/12 =
    // 0.0013 m^2 < min_eigen_value of variance: every layer-2 cell counts as planar, as in FAST-LIVO2.)
    if (p.layer <= 1) {
      EXPECT_GT(std::max(std::abs(p.normal.x()), std::abs(p.normal.z())), 0.99);
    }
  });
  EXPECT_EQ(at_layer[0], 0);  // the corner is not one plane
  EXPECT_GE(at_layer[1], 4);  // children holding only floor or only wall
  const VoxelMapStats s = map.stats();
  EXPECT_GT(at_layer[2], 0);  // the corner cells split once more
  EXPECT_GT(s.nodes, 7u);      // root + 6 non-empty children + grandchildren
  EXPECT_GT(s.frozen_leaves, 0u);
}

TEST(Octree, FreezingAtMaxPointsFreesThePoints) {
  VoxelMap map;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 0.5);
  auto add = [&](int n) {
    std::vector<PointWithCov> v;
    for (int i = 0; i < n; ++i) v.push_back(withCov(Vec3(u(rng), 0.2, u(rng)), Vec3(3, -2, 0)));
    map.insert(v);
  };
  add(49);
  VoxelMapStats s = map.stats();
  EXPECT_EQ(s.stored_points, 49u);
  EXPECT_EQ(s.frozen_leaves, 0u);
  const std::size_t bytes_before = s.bytes;
  add(1);
  s = map.stats();
  EXPECT_EQ(s.stored_points, 0u);
  EXPECT_EQ(s.frozen_leaves, 1u);
  EXPECT_LT(s.bytes, bytes_before);
  Plane frozen;
  map.forEachPlane([&](const VoxelKey&, const Plane& p) { frozen = p; });
  EXPECT_EQ(frozen.num_points, 50);  // a final refit used every point
  add(30);  // ignored: the plane never changes again
  map.forEachPlane([&](const VoxelKey&, const Plane& p) {
    EXPECT_EQ(p.num_points, 50);
    EXPECT_EQ(p.center, frozen.center);
  });
  EXPECT_EQ(map.stats().stored_points, 0u);

  // Non-plane leaves at max_layer freeze the same way: a volume with a tight planarity threshold.
  VoxelMapConfig cfg;
  cfg.min_eigen_value = 1e-4;
  VoxelMap vol(cfg);
  std::vector<PointWithCov> v;
  for (int i = 0; i < 64 * 100; ++i) v.push_back(withCov(Vec3(u(rng), u(rng), u(rng)), Vec3(3, -2, 0)));
  vol.insert(v);
  s = vol.stats();
  EXPECT_EQ(s.planes, 0u);
  EXPECT_EQ(s.nodes, 1u + 8u + 64u);
  EXPECT_EQ(s.frozen_leaves, 64u);
  EXPECT_EQ(s.stored_points, 0u);
}
