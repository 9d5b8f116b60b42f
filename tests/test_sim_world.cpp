// libs/sim: BVH raycasts vs brute-force raycasts (room and street worlds), the corridor's degeneracy
// (no surface along its axis within LiDAR range), world.seed apart from the noise.
#include "sim_test_util.hpp"

#include "livo/sim/random.hpp"
#include "livo/sim/simulator.hpp"
#include "livo/sim/world_gen.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace livo;
using namespace livo::sim;
using namespace livo::sim::test;

namespace {

Utime t0Utime(const Simulator& sim, double t) { return sim.startUtime() + fromSeconds(t); }

}  // namespace

TEST(SimWorld, BvhRaycastMatchesBruteForce) {
  for (const std::string kind : {"room", "street"}) {
    SCOPED_TRACE(kind);
    const SimScenario sc = makeScenario(kind, kind == "street" ? "spinning32" : "avia");
    Simulator sim(sc);
    SplitMix rng(11);
    int hits = 0;
    for (int k = 0; k < 3000; ++k) {
      const auto& path = sim.trajectory().path();
      const Vec3 o = path[static_cast<std::size_t>(rng.next() % path.size())] + Vec3(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), 0.0);
      const Vec3 d = Vec3(rng.gaussian(), rng.gaussian(), rng.gaussian()).normalized();
      const Hit a = sim.world().raycast(o, d, 150.0), b = sim.world().raycastBruteForce(o, d, 150.0);
      ASSERT_EQ(a.valid, b.valid);
      if (!a.valid) continue;
      ++hits;
      ASSERT_EQ(a.surface, b.surface);
      ASSERT_EQ(a.distance, b.distance);
      ASSERT_EQ(a.albedo, b.albedo);
    }
    EXPECT_GT(hits, 1000);
  }
}

TEST(SimWorld, CorridorHasNoSurfaceAlongItsAxisWithinLidarRange) {
  const SimScenario sc = loadScenarioFile(std::string(LIVO_SOURCE_DIR) + "/config/sim/corridor.yaml");
  Simulator sim(sc);
  double x_min = 1e9, x_max = -1e9;
  std::size_t hits = 0;
  for (double t = 0.0; t <= sc.duration_s; t += 1.0) {
    const Pose T = sim.T_world_lidar(t0Utime(sim, t));
    x_min = std::min(x_min, T.translation().x());
    x_max = std::max(x_max, T.translation().x());
    const int n = 1500;  // Fibonacci sphere of directions
    for (int k = 0; k < n; ++k) {
      const double z = 1.0 - 2.0 * (k + 0.5) / n, r = std::sqrt(1.0 - z * z), phi = k * 2.399963229728653;
      const Hit h = sim.world().raycast(T.translation(), Vec3(r * std::cos(phi), r * std::sin(phi), z), sc.lidar.max_range_m);
      if (!h.valid) continue;
      ++hits;
      ASSERT_EQ(h.normal.x(), 0.0) << "surface " << h.surface << " at " << h.point.transpose();
    }
  }
  EXPECT_GT(hits, 50000u);
  EXPECT_GE(x_max - x_min, 60.0);  // the walk covers >= 60 m of corridor
}

namespace livo::sim {
namespace {

// world.seed keeps the world while the scenario's seed changes the noise; unset, the world follows the
// scenario's seed as before.
TEST(SimWorld, WorldSeedKeepsTheWorldApartFromTheNoise) {
  auto world = [](std::int64_t seed, std::int64_t world_seed, double start_m = 0.0) {
    SimScenario s = test::makeScenario("street", "avia", true);
    s.seed = seed;
    s.world.seed = world_seed;
    s.trajectory.start_m = start_m;
    return Simulator(s);
  };
  auto same = [](const World& a, const World& b) {
    if (a.primitives().size() != b.primitives().size()) return false;
    for (std::size_t i = 0; i < a.primitives().size(); ++i)
      if (a.primitives()[i].center != b.primitives()[i].center || a.primitives()[i].half != b.primitives()[i].half)
        return false;
    return true;
  };
  const Simulator a = world(1, 7), b = world(2, 7), c = world(1, -1), d = world(2, -1);
  EXPECT_TRUE(same(a.world(), b.world()));
  EXPECT_FALSE(same(c.world(), d.world()));
  // The same world seen with other noise: the scans differ (ranges, and so which beams hit).
  const LidarScan sa = a.lidarScan(10), sb = b.lidarScan(10);
  bool differ = sa.points.size() != sb.points.size();
  for (std::size_t i = 0; !differ && i < sa.points.size(); ++i) differ = sa.points[i].p_lidar != sb.points[i].p_lidar;
  EXPECT_TRUE(differ) << "other sensor noise";
  EXPECT_NEAR(double(sa.points.size()), double(sb.points.size()), 0.01 * double(sa.points.size())) << "one world";
  // With world.seed, another start on the path moves the robot, not the world (a second run in it).
  const Simulator e = world(2, 7, 150.0);
  EXPECT_TRUE(same(a.world(), e.world()));
  EXPECT_GT((e.T_world_imu(e.lidarUtime(0)).translation() - a.T_world_imu(a.lidarUtime(0)).translation()).norm(), 10.0);
}

}  // namespace
}  // namespace livo::sim
