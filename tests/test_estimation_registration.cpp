// Scan-to-map registration without a motion model (libs/estimation scan_registration): a ray-cast room
// with a known offset of 1 m, 30-48 deg of yaw and up to 8 deg of roll (oracle), the same from a scan
// too sparse for normals and from a search map made of the map's planes; a corridor's axis reported as
// unconstrained and not fixed; the failures named; and every real Hilti 2021 scan registered against
// the map of the ones before it with no IMU and no motion model, scored against the reference poses
// (LIVO_REG_VERBOSE=1 prints every scan's step error).
// livo-test-deps: livo_eval
#include "livo/common/timing.hpp"
#include "livo/estimation/scan_registration.hpp"
#include "livo/eval/metrics.hpp"
#include "livo/eval/tum.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/map/voxel_key.hpp"
#include "livo/map/voxel_map.hpp"

#include "test_skip.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

using namespace livo;

namespace {

constexpr double kDeg = M_PI / 180.0;

// ------------------------------------------------------------------ a ray-cast world of boxes
struct Box {
  Vec3 lo, hi;
  bool room = false;  ///< the sensor is inside: the ray hits its far side (walls, floor, ceiling)
};

/// Distance along the unit ray o + t d to the box's surface (its far side for a room), or -1.
double rayBox(const Vec3& o, const Vec3& d, const Box& b) {
  double t0 = -1e30, t1 = 1e30;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-12) {
      if (o[i] < b.lo[i] || o[i] > b.hi[i]) return -1;
      continue;
    }
    double a = (b.lo[i] - o[i]) / d[i], c = (b.hi[i] - o[i]) / d[i];
    if (a > c) std::swap(a, c);
    t0 = std::max(t0, a);
    t1 = std::min(t1, c);
  }
  if (t0 > t1) return -1;
  if (b.room) return t1 > 0 ? t1 : -1;
  return t0 > 0 ? t0 : -1;
}

/// A spinning LiDAR at T_world_sensor: `beams` rings over +-vfov_deg, one return per az_step_deg,
/// range noise sigma_r (m), returns beyond max_range dropped. Points in the sensor frame.
std::vector<Vec3> castScan(const std::vector<Box>& world, const Pose& T_world_sensor, std::mt19937& rng,
                           int beams = 32, double vfov_deg = 30, double az_step_deg = 0.4, double max_range = 20.0,
                           double sigma_r = 0.01) {
  std::normal_distribution<double> noise(0.0, sigma_r);
  std::uniform_real_distribution<double> jitter(0.0, az_step_deg);
  std::vector<Vec3> pts;
  const Vec3 o = T_world_sensor.translation();
  const double az0 = jitter(rng);  // another sampling of the surfaces on every call
  for (int b = 0; b < beams; ++b) {
    const double el = (-vfov_deg + 2 * vfov_deg * b / (beams - 1)) * kDeg;
    for (double az = az0; az < 360.0; az += az_step_deg) {
      const Vec3 d_s(std::cos(el) * std::cos(az * kDeg), std::cos(el) * std::sin(az * kDeg), std::sin(el));
      const Vec3 d = T_world_sensor.linear() * d_s;
      double best = -1;
      for (const Box& box : world) {
        const double t = rayBox(o, d, box);
        if (t > 0 && (best < 0 || t < best)) best = t;
      }
      if (best < 0.5 || best > max_range) continue;
      pts.push_back(d_s * (best + noise(rng)));
    }
  }
  return pts;
}

/// A furnished room, 14 x 9 x 3 m: pillars, cabinets and a table break its symmetries.
std::vector<Box> room() {
  return {{Vec3(-6, -4, -1.2), Vec3(8, 5, 1.8), true},
          {Vec3(2.0, 1.5, -1.2), Vec3(2.6, 2.1, 1.8)},     // pillar
          {Vec3(-3.5, -2.0, -1.2), Vec3(-3.0, -1.5, 1.8)},  // pillar
          {Vec3(4.0, -4.0, -1.2), Vec3(6.5, -3.4, 0.8)},    // cabinet on the south wall
          {Vec3(-6.0, 2.0, -1.2), Vec3(-5.4, 4.5, 0.5)},    // cabinet on the west wall
          {Vec3(-1.0, 2.5, -0.45), Vec3(1.0, 3.5, -0.4)},   // table top
          {Vec3(5.0, 1.0, -1.2), Vec3(6.0, 2.0, -0.2)}};    // crate
}

/// A straight corridor 2.5 m wide and 3 m high, far longer than the LiDAR's range: nothing tells
/// positions along x apart.
std::vector<Box> corridor() { return {{Vec3(-200, -1.25, -1.2), Vec3(200, 1.25, 1.8), true}}; }

Pose poseOf(double x, double y, double z, double yaw) {
  Pose T = Pose::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
  T.translation() = Vec3(x, y, z);
  return T;
}

std::vector<PointWithCov> toWorld(const std::vector<BodyPoint>& pts, const Pose& T) {
  std::vector<PointWithCov> out;
  out.reserve(pts.size());
  const Mat3 R = T.linear();
  for (const BodyPoint& p : pts) out.push_back({T * p.p_imu, R * p.cov_imu * R.transpose()});
  return out;
}

std::vector<Vec3> worldPoints(const std::vector<BodyPoint>& pts, const Pose& T) {
  std::vector<Vec3> out;
  out.reserve(pts.size());
  for (const BodyPoint& p : pts) out.push_back(T * p.p_imu);
  return out;
}

ScanRegistrationConfig simConfig() {
  ScanRegistrationConfig c;
  c.range_noise_m = 0.02;  // what the map and the registration assume (the simulated noise is 1 cm)
  c.voxel_size_m = 0.5;
  return c;
}

/// A map (voxel map + search map) of the scan taken at `T_map` of `world`.
struct World {
  VoxelMap map;
  SearchMap search;
  World(const std::vector<Box>& world, const Pose& T_map, const ScanRegistration& reg, std::mt19937& rng)
      : map(VoxelMapConfig{}), search(reg.config()) {
    for (int k = 0; k < 2; ++k) {  // two sweeps: a denser first map, as a rig at rest would have
      const auto pts = reg.bodyPoints(castScan(world, T_map, rng));
      map.insert(toWorld(pts, T_map));
      search.addPoints(worldPoints(pts, T_map));
    }
  }
};

double yawOf(const Mat3& R) { return std::atan2(R(1, 0), R(0, 0)); }

}  // namespace

// ------------------------------------------------------------------------------------ synthetic
TEST(ScanRegistration, RecoversAOneMetreAnd30To48DegreeOffsetInARoom) {
  std::mt19937 rng(7);
  const ScanRegistration reg(simConfig());
  const World w(room(), Pose::Identity(), reg, rng);
  // The rig moved 1 m, turned and tilted; the initial guess is where it was (no motion model).
  for (const auto& [yaw_deg, roll_deg] : {std::pair{30.0, 0.0}, {-40.0, 6.0}, {48.0, -8.0}}) {
    const double a = yaw_deg * kDeg;
    Pose truth = poseOf(std::cos(a + 0.3), std::sin(a + 0.3), 0.05, a);  // |t| about 1 m
    truth.linear() = truth.linear() * Eigen::AngleAxisd(roll_deg * kDeg, Vec3::UnitX()).toRotationMatrix();
    const auto scan = castScan(room(), truth, rng);
    const auto r = reg.align(scan, w.map, w.search, Pose::Identity(), SearchBounds{1.2, 60 * kDeg, 15 * kDeg});
    const double dp = (r.T_world_body.translation() - truth.translation()).norm();
    const double dr = rotationAngle(truth.linear().transpose() * r.T_world_body.linear()) / kDeg;
    std::printf("room, yaw %+.0f roll %+.0f deg: %s, error %.1f mm %.3f deg, matched %d/%d, rms %.1f mm, share %.2f, "
                "search %d/%d%s\n",
                yaw_deg, roll_deg, r.success ? "ok" : r.reason.c_str(), dp * 1e3, dr, r.matched, r.points,
                r.rms_residual_m * 1e3, r.weakest_share, r.search_hits, r.search_points,
                r.search_ambiguous ? " ambiguous" : "");
    EXPECT_TRUE(r.success) << r.reason;
    EXPECT_LT(dp, 0.02);
    EXPECT_LT(dr, 0.2);
    EXPECT_TRUE(r.unconstrained_directions.empty());
    EXPECT_GT(r.weakest_share, 0.2);
    EXPECT_FALSE(r.search_ambiguous);
    // The information is positive definite and its position block of the order the fix's accuracy says.
    const Eigen::SelfAdjointEigenSolver<Mat6> es(r.information);
    EXPECT_GT(es.eigenvalues().minCoeff(), 0.0);
    const Mat3 pos_cov = r.information.inverse().bottomRightCorner<3, 3>();
    EXPECT_LT(std::sqrt(pos_cov.trace()), 0.01);
  }
}

TEST(ScanRegistration, WithoutPlanarPatchesTheOccupancySearchesTheYaw) {
  // A scan thinned to one point per voxel has no planar patch (a patch needs 6 points in a voxel):
  // the yaw comes from the occupancy search instead of the normals.
  std::mt19937 rng(19);
  const ScanRegistration reg(simConfig());
  const World w(room(), Pose::Identity(), reg, rng);
  const Pose truth = poseOf(0.6, -0.7, 0.0, -35 * kDeg);
  std::vector<Vec3> sparse;
  std::unordered_set<VoxelKey, VoxelKeyHash> seen;
  for (const Vec3& p : castScan(room(), truth, rng))
    if (seen.insert(VoxelKey::fromPoint(p, reg.config().voxel_size_m)).second) sparse.push_back(p);
  const auto r = reg.align(sparse, w.map, w.search, Pose::Identity(), SearchBounds{1.2, 60 * kDeg});
  std::printf("sparse room (%zu points): %s, error %.1f mm %.3f deg\n", sparse.size(), r.success ? "ok" : r.reason.c_str(),
              (r.T_world_body.translation() - truth.translation()).norm() * 1e3,
              rotationAngle(truth.linear().transpose() * r.T_world_body.linear()) / kDeg);
  EXPECT_FALSE(r.rotation_searched);
  EXPECT_TRUE(r.searched);
  EXPECT_TRUE(r.success) << r.reason;
  EXPECT_LT((r.T_world_body.translation() - truth.translation()).norm(), 0.03);
  EXPECT_LT(rotationAngle(truth.linear().transpose() * r.T_world_body.linear()), 0.3 * kDeg);
}

TEST(ScanRegistration, TheMapsPlanesAloneServeTheSearch) {
  // A lost filter's map holds planes, not points (frozen leaves free theirs): the search map is
  // rasterised from the plane leaves.
  std::mt19937 rng(11);
  const ScanRegistration reg(simConfig());
  World w(room(), Pose::Identity(), reg, rng);
  SearchMap planes(reg.config());
  planes.addPlanes(w.map);
  ASSERT_FALSE(planes.empty());
  const Pose truth = poseOf(-0.7, 0.7, 0.0, 35 * kDeg);
  const auto r = reg.align(castScan(room(), truth, rng), w.map, planes, Pose::Identity(), SearchBounds{1.2, 60 * kDeg});
  EXPECT_TRUE(r.success) << r.reason;
  EXPECT_LT((r.T_world_body.translation() - truth.translation()).norm(), 0.02);
  EXPECT_LT(rotationAngle(truth.linear().transpose() * r.T_world_body.linear()), 0.2 * kDeg);
}

TEST(ScanRegistration, InACorridorTheAxisIsUnconstrainedAndNotFixed) {
  std::mt19937 rng(13);
  const ScanRegistration reg(simConfig());
  const World w(corridor(), Pose::Identity(), reg, rng);
  const Pose truth = poseOf(0.8, 0.3, 0.05, 30 * kDeg);
  const Pose init = Pose::Identity();
  const auto r = reg.align(castScan(corridor(), truth, rng), w.map, w.search, init, SearchBounds{1.2, 60 * kDeg});
  std::printf("corridor: %s, position %.3f %.3f %.3f yaw %.2f deg, share %.3f along (%.2f %.2f %.2f), %zu free%s\n",
              r.success ? "ok" : r.reason.c_str(), r.T_world_body.translation().x(), r.T_world_body.translation().y(),
              r.T_world_body.translation().z(), yawOf(r.T_world_body.linear()) / kDeg, r.weakest_share,
              r.weakest_direction.x(), r.weakest_direction.y(), r.weakest_direction.z(),
              r.unconstrained_directions.size(), r.search_ambiguous ? ", search ambiguous" : "");
  EXPECT_TRUE(r.success) << r.reason;
  // What the corridor tells: lateral position, height and every rotation.
  EXPECT_NEAR(r.T_world_body.translation().y(), truth.translation().y(), 0.02);
  EXPECT_NEAR(r.T_world_body.translation().z(), truth.translation().z(), 0.02);
  EXPECT_LT(rotationAngle(truth.linear().transpose() * r.T_world_body.linear()), 0.3 * kDeg);
  // What it does not: the axis is reported, the position along it stays the initial guess, and the
  // information along it is zero.
  EXPECT_LT(r.weakest_share, reg.config().min_share);
  EXPECT_GT(std::abs(r.weakest_direction.x()), 0.99);
  ASSERT_EQ(r.unconstrained_directions.size(), 1u);
  EXPECT_GT(std::abs(r.unconstrained_directions[0].x()), 0.99);
  const Vec3& u = r.unconstrained_directions[0];
  EXPECT_NEAR(u.dot(r.T_world_body.translation() - init.translation()), 0.0, 1e-9);
  Eigen::Matrix<double, 6, 1> along_u = Eigen::Matrix<double, 6, 1>::Zero();
  along_u.tail<3>() = u;
  EXPECT_NEAR(along_u.dot(r.information * along_u), 0.0, 1e-9 * r.information.trace());
}

TEST(ScanRegistration, NamesItsFailures) {
  std::mt19937 rng(17);
  const ScanRegistration reg(simConfig());
  const World w(room(), Pose::Identity(), reg, rng);
  const auto scan = castScan(room(), poseOf(0.5, 0, 0, 0.3), rng);
  // Too few points.
  const std::vector<Vec3> few(scan.begin(), scan.begin() + 5);
  auto r = reg.align(few, w.map, w.search, Pose::Identity(), SearchBounds{1.0, 0.5});
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.failure, RegistrationFailure::TooFewPoints);
  // An empty map.
  const VoxelMap empty;
  const SearchMap no_search(reg.config());
  r = reg.align(scan, empty, no_search, Pose::Identity(), SearchBounds{1.0, 0.5});
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.failure, RegistrationFailure::EmptyMap);
  EXPECT_FALSE(r.reason.empty());
  // A pose far outside the bounds: the room's map seen from 30 m away matches nothing.
  r = reg.align(scan, w.map, w.search, poseOf(30, 0, 0, 0), SearchBounds{1.0, 0.5});
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.failure, RegistrationFailure::None);
}

// ------------------------------------------------------------------------------------ real data
namespace {

std::vector<Vec3> readScan(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<Vec3> pts;
  float xyz[3];
  while (in.read(reinterpret_cast<char*>(xyz), sizeof(xyz))) pts.emplace_back(xyz[0], xyz[1], xyz[2]);
  return pts;
}

}  // namespace

TEST(ScanRegistrationHilti, EveryScanAgainstTheMapOfTheOnesBeforeWithoutImu) {
  const std::string dir = std::string(LIVO_SHARED_DATA) + "/hilti_balm_scans";
  if (!std::ifstream(dir + "/poses_tum.txt") || !std::ifstream(dir + "/scan_000.bin"))
    LIVO_SKIP() << "no ../shared/data/hilti_balm_scans";
  const Trajectory ref = readTum(dir + "/poses_tum.txt");
  ASSERT_EQ(ref.size(), 177u);

  // The odometry's Hilti configuration (config/hilti22.yaml: voxel 0.4 m, planes thinner than
  // 1e-4 m^2, 100 points a leaf; lidar range noise 2 cm, bearing 0.05 deg).
  VoxelMapConfig vcfg;
  vcfg.voxel_size_m = 0.4;
  vcfg.min_eigen_value = 1e-4;
  vcfg.max_points = 100;
  LioConfig lio;
  const ScanRegistration reg(ScanRegistrationConfig::from(lio, vcfg, 20));
  VoxelMap map(vcfg);
  SearchMap search(reg.config());
  // Search bounds from the data's physical limits: a handheld rig at 2 Hz moves at most about 2 m/s,
  // turns about the vertical at most about 120 deg/s and tilts at most about 40 deg/s (the reference:
  // at most 0.83 m, 48 deg and 16.5 deg of roll / pitch between scans).
  const SearchBounds bounds{1.0, 60 * kDeg, 20 * kDeg};

  const bool verbose = std::getenv("LIVO_REG_VERBOSE") != nullptr;
  std::vector<Pose> est, gt;
  int failed = 0, ambiguous = 0;
  double min_share = 1.0;
  Stopwatch sw;
  double reg_ms = 0, max_reg_ms = 0;
  for (std::size_t k = 0; k < ref.size(); ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "/scan_%03zu.bin", k);
    const std::vector<BodyPoint> pts = reg.bodyPoints(readScan(dir + name));
    ASSERT_GT(pts.size(), 10000u) << name;
    Pose T = ref.front().T_world_body;  // the first scan defines the frame
    if (k > 0) {
      Stopwatch one;
      const auto r = reg.align(pts, map, search, est.back(), bounds);  // no motion model: the last pose
      const double ms = one.elapsedMs();
      reg_ms += ms;
      max_reg_ms = std::max(max_reg_ms, ms);
      T = r.T_world_body;
      if (verbose || !r.success) {
        const Pose ref_step = ref[k - 1].T_world_body.inverse() * ref[k].T_world_body;
        const Pose E = ref_step.inverse() * (est.back().inverse() * r.T_world_body);
        const Pose Es = ref_step.inverse() * (est.back().inverse() * r.T_search);
        std::printf("scan %3zu: %s step %.2f m %.1f deg, err %.3f m %.2f deg (search %.3f m %.2f deg), matched %d/%d "
                    "rms %.1f mm share %.2f, search %d/%d%s, %d hyp %d it, %.0f ms\n",
                    k, r.success ? "ok" : r.reason.c_str(), ref_step.translation().norm(),
                    rotationAngle(ref_step.linear()) / kDeg, E.translation().norm(), rotationAngle(E.linear()) / kDeg,
                    Es.translation().norm(), rotationAngle(Es.linear()) / kDeg, r.matched, r.points,
                    r.rms_residual_m * 1e3, r.weakest_share, r.search_hits, r.search_points,
                    r.search_ambiguous ? " ambiguous" : "", r.hypotheses_tried, r.iterations, ms);
      }
      ambiguous += r.search_ambiguous ? 1 : 0;
      min_share = std::min(min_share, r.weakest_share);
      if (!r.success) {  // as the odometry: a scan that failed to register stays out of the map
        ++failed;
        est.push_back(est.back());
        gt.push_back(ref[k].T_world_body);
        continue;
      }
    }
    est.push_back(T);
    gt.push_back(ref[k].T_world_body);
    // Into the map at the registered pose, as the odometry inserts a registered scan (no pose
    // covariance: the point's own noise). The whole 74.5 m path fits the odometry's 200 m local map.
    map.insert(toWorld(pts, T));
    search.addPoints(worldPoints(pts, T));
  }
  const double total_s = sw.elapsedMs() / 1e3;

  const RpeResult rpe1 = computeRpe(gt, est, 1.0);
  const RpeResult rpe5 = computeRpe(gt, est, 5.0);
  double worst_m = 0, worst_deg = 0;
  for (std::size_t k = 1; k < est.size(); ++k) {
    const Pose E = (gt[k - 1].inverse() * gt[k]).inverse() * (est[k - 1].inverse() * est[k]);
    worst_m = std::max(worst_m, E.translation().norm());
    worst_deg = std::max(worst_deg, rotationAngle(E.linear()) / kDeg);
  }
  std::printf("Hilti, %zu scans, %d failed, %d ambiguous, weakest share >= %.2f: RPE 1 m %.2f %% %.3f deg/m (%zu "
              "pairs), 5 m %.2f %% %.3f deg/m (%zu pairs); worst step %.1f mm %.2f deg; registration mean %.0f ms "
              "max %.0f ms; total %.1f s\n",
              est.size(), failed, ambiguous, min_share, rpe1.translation_pct, rpe1.rotation_deg_per_m,
              rpe1.translation_m.count, rpe5.translation_pct, rpe5.rotation_deg_per_m, rpe5.translation_m.count,
              worst_m * 1e3, worst_deg, reg_ms / double(est.size() - 1), max_reg_ms, total_s);
  // Bounds at about twice what was measured on 2026-12-07 (0 of 176 registrations failed; RPE over
  // 1 m 1.24 % and 0.117 deg/m, over 5 m 0.40 % and 0.032 deg/m; worst step 32.6 mm and 0.59 deg against
  // reference poses whose consecutive scans agree to a few centimetres; 160 ms a registration, 38 s
  // in all on 2 shared cores).
  EXPECT_EQ(failed, 0);
  EXPECT_LT(rpe1.translation_pct, 2.5);
  EXPECT_LT(rpe1.rotation_deg_per_m, 0.25);
  EXPECT_LT(rpe5.translation_pct, 0.8);
  EXPECT_LT(rpe5.rotation_deg_per_m, 0.065);
  EXPECT_LT(worst_m, 0.070);
  EXPECT_LT(worst_deg, 1.2);
}
