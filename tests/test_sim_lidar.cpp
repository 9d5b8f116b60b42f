// libs/sim: LiDAR points on the world's surfaces at their own times; blind, max-range and grazing
// returns dropped.
#include "sim_test_util.hpp"

#include "livo/sim/simulator.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace livo;
using namespace livo::sim;
using namespace livo::sim::test;

// ---------------------------------------------------------------- LiDAR

TEST(SimLidar, PointsLieOnTheSurfacesAtTheirOwnTimes) {
  for (const std::string model : {"avia", "mid360", "spinning32"}) {
    SCOPED_TRACE(model);
    SimScenario sc = makeScenario("room", model);
    sc.extrinsics.T_imu_lidar.translation() = Vec3(0.05, -0.02, 0.08);
    sc.extrinsics.T_imu_lidar.linear() = expSO3(Vec3(0.02, -0.03, 0.1));
    Simulator sim(sc);
    const std::int64_t j = 33;  // moving
    const LidarScan scan = sim.lidarScan(j);
    EXPECT_EQ(scan.utime, sim.startUtime() + 3'300'000);
    EXPECT_EQ(scan.sensor, model);
    const std::size_t rays = static_cast<std::size_t>(sim.lidarPattern().firingsPerScan()) * sim.lidarPattern().lasers();
    EXPECT_EQ(rays, model == "avia" ? 24000u : model == "mid360" ? 20000u : 32768u);
    EXPECT_GT(scan.points.size(), rays * 7 / 10);  // a closed room returns almost every ray
    const Pose T_start = sim.T_world_lidar(scan.utime);
    std::size_t checked = 0, off_with_start_pose = 0;
    for (std::size_t i = 0; i < scan.points.size(); i += 5) {
      const LidarPoint& p = scan.points[i];
      ASSERT_GE(p.time_offset_s, 0.f);
      ASSERT_LT(p.time_offset_s, 0.1f);
      ASSERT_GE(p.ring, 0);
      ASSERT_LT(p.ring, sim.lidarPattern().lasers());
      const double t = sim.relTime(scan.utime) + static_cast<double>(p.time_offset_s);
      const Pose T = sim.trajectory().pose(t) * sc.extrinsics.T_imu_lidar;
      const Vec3 p_world = T * p.p_lidar.cast<double>();
      ASSERT_LT(sim.world().distanceToSurface(p_world), 2e-5 * (1.0 + p.p_lidar.norm())) << "point " << i;
      off_with_start_pose += sim.world().distanceToSurface(T_start * p.p_lidar.cast<double>()) > 0.005;
      ++checked;
    }
    // Motion distortion is real: the scan-start pose puts many points off the surfaces.
    EXPECT_GT(off_with_start_pose, checked / 4);
  }
}

TEST(SimLidar, BlindMaxRangeAndGrazingReturnsAreDropped) {
  SimScenario sc = makeScenario("wall");
  // The sensor starts 0.8 m in front of the wall, facing it: a beam at angle a from the normal has
  // range 0.8 / cos(a). Blind 0.85 m drops a < 19.7 deg, incidence > 30 deg is grazing, max range
  // 0.95 m drops a > 32.6 deg (the Avia reaches 38.6 deg).
  sc.world.size_m = {0.8, 40.0, 20.0};
  sc.lidar.range_noise_m = 0.002;
  sc.lidar.blind_m = 0.85;
  sc.lidar.max_range_m = 0.95;
  sc.lidar.max_incidence_deg = 30.0;
  Simulator sim(sc);
  LidarStats st;
  const LidarScan scan = sim.lidarScan(0, &st);  // at rest
  ASSERT_GT(scan.points.size(), 100u);
  EXPECT_GT(st.blind, 1000u);
  EXPECT_GT(st.no_return, 200u);
  EXPECT_GT(st.grazing, 200u);
  EXPECT_EQ(st.points + st.blind + st.no_return + st.grazing, st.rays);
  for (const auto& p : scan.points) {
    const double r = p.p_lidar.norm();
    ASSERT_GE(r, sc.lidar.blind_m);
    ASSERT_LE(r, sc.lidar.max_range_m);
    // The wall normal is -x of the world; the sensor faces +x at rest (no beam noise here).
    const Vec3 dir_world = sim.T_world_lidar(scan.utime).linear() * p.p_lidar.cast<double>().normalized();
    ASSERT_GE(dir_world.x(), std::cos(30.0 * kPi / 180.0) - 1e-6);
  }
}

// lidar.freeze_s: every scan starting inside the interval repeats the points of the last scan before
// it, stamped with its own time; the scans around it are the simulator's own.
TEST(SimLidar, AFrozenLidarRepeatsItsLastScan) {
  SimScenario sc = makeScenario("room", "avia");
  sc.lidar.freeze_s = {3.0, 3.5};
  Simulator frozen(sc);
  const LidarScan before = frozen.lidarScan(29);  // 2.9 s: the last scan before the freeze
  for (std::int64_t j = 30; j < 35; ++j) {
    const LidarScan s = frozen.lidarScan(j);
    EXPECT_EQ(s.utime, frozen.startUtime() + j * 100'000);
    ASSERT_EQ(s.points.size(), before.points.size()) << j;
    for (std::size_t i = 0; i < s.points.size(); i += 97) ASSERT_EQ(s.points[i].p_lidar, before.points[i].p_lidar) << j;
  }
  const LidarScan after = frozen.lidarScan(35);  // 3.5 s: the freeze is over
  const LidarScan own = Simulator(makeScenario("room", "avia")).lidarScan(35);
  ASSERT_EQ(after.points.size(), own.points.size());
  for (std::size_t i = 0; i < own.points.size(); i += 97) EXPECT_EQ(after.points[i].p_lidar, own.points[i].p_lidar);
}
