// libs/estimation: error-state algebra, point-to-plane Jacobians vs numeric differences, the iterated
// LiDAR update vs the known pose and vs a batch Gauss-Newton solution, the degeneracy metric, real KITTI
// scans. The IMU (propagation, initialisation, its config) is in test_estimation_imu.cpp.
// livo-test-deps: livo_map livo_eval
#include "livo/estimation/health.hpp"
#include "livo/estimation/imu.hpp"
#include "livo/estimation/imu_init.hpp"
#include "livo/estimation/lio_update.hpp"
#include "livo/estimation/state.hpp"
#include "livo/eval/tum.hpp"
#include "livo/map/point_cov.hpp"

#include "estimation_test_util.hpp"
#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace livo;
using livo_test::randomState;


TEST(State, BoxPlusMinusAreInverse) {
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0, 0.3);
  for (int k = 0; k < 20; ++k) {
    const NavState x = randomState(rng);
    StateVec d;
    for (int i = 0; i < kStateDim; ++i) d[i] = n(rng);
    const NavState y = x.boxplus(d);
    EXPECT_NEAR((y.boxminus(x) - d).norm(), 0.0, 1e-9);
    EXPECT_NEAR(x.boxplus(y.boxminus(x)).boxminus(y).norm(), 0.0, 1e-9);
  }
}

// ---- LiDAR update ----

TEST(LioUpdate, ResidualJacobianMatchesNumericDifferences) {
  std::mt19937 rng(5);
  for (int k = 0; k < 20; ++k) {
    const NavState x = randomState(rng);
    const Vec3 p_imu(3.0 - k * 0.2, 1.5, -0.7 + 0.1 * k);
    const Vec3 n = Vec3(0.3, -0.5, 0.8).normalized();
    const double d = -1.2;
    const PlaneResidual r = planeResidual(x, p_imu, n, d);
    const double eps = 1e-7;
    for (int i = 0; i < 6; ++i) {
      StateVec dv = StateVec::Zero();
      dv[i] = eps;
      const double zp = planeResidual(x.boxplus(dv), p_imu, n, d).residual;
      const double zm = planeResidual(x.boxplus(-dv), p_imu, n, d).residual;
      EXPECT_NEAR(r.h[i], (zp - zm) / (2 * eps), 1e-6) << "column " << i;
    }
  }
}

namespace {

// Three families of walls around the origin, sampled densely, as a world point cloud.
std::vector<Vec3> boxScene(std::mt19937& rng, int per_face) {
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  std::vector<Vec3> pts;
  for (int i = 0; i < per_face; ++i) {
    pts.emplace_back(5.0, u(rng), 0.5 * u(rng));
    pts.emplace_back(-5.0, u(rng), 0.5 * u(rng));
    pts.emplace_back(u(rng), 6.0, 0.5 * u(rng));
    pts.emplace_back(u(rng), -3.0, 0.5 * u(rng));
    pts.emplace_back(u(rng), u(rng), -2.0);
    pts.emplace_back(u(rng), u(rng), 2.5);
  }
  return pts;
}

// World points `scene` with Gaussian noise and covariance 2.5e-5 * I (5 mm), as a map's input.
std::vector<PointWithCov> noisyMapPoints(const std::vector<Vec3>& scene, std::mt19937& rng,
                                         std::normal_distribution<double>& noise) {
  std::vector<PointWithCov> mpts;
  for (const auto& p : scene) {
    PointWithCov pw;
    pw.p_world = p + Vec3(noise(rng), noise(rng), noise(rng));
    pw.cov_world = Mat3::Identity() * 2.5e-5;
    mpts.push_back(pw);
  }
  return mpts;
}

// Body points of world points `scene` seen from `truth`, with Gaussian noise and covariance var * I.
std::vector<BodyPoint> scanFrom(const NavState& truth, const std::vector<Vec3>& scene, std::mt19937& rng,
                                std::normal_distribution<double>& noise, double var) {
  std::vector<BodyPoint> body;
  for (const auto& p : scene) {
    BodyPoint bp;
    bp.p_imu = truth.R_world_imu.transpose() * (p - truth.p_world_imu) + Vec3(noise(rng), noise(rng), noise(rng));
    bp.cov_imu = Mat3::Identity() * var;
    body.push_back(bp);
  }
  return body;
}

}  // namespace

TEST(LioUpdate, RecoversPerturbedPoseInBoxScene) {
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0, 0.005);
  VoxelMapConfig mc;
  VoxelMap map(mc);
  const std::vector<PointWithCov> mpts = noisyMapPoints(boxScene(rng, 20000), rng, noise);
  map.insert(mpts);
  ASSERT_GT(map.numPlanes(), 100u);

  // True pose and a scan of body points seeing the scene.
  NavState truth;
  truth.R_world_imu = expSO3(Vec3(0.05, -0.03, 0.4));
  truth.p_world_imu = Vec3(0.5, 0.3, 0.1);
  const std::vector<BodyPoint> body = scanFrom(truth, boxScene(rng, 800), rng, noise, 2.5e-5);
  // Prior: 8 cm / 1.5 deg off, with a covariance that covers it.
  NavState x = truth;
  x.p_world_imu += Vec3(0.06, -0.05, 0.02);
  x.R_world_imu = truth.R_world_imu * expSO3(Vec3(0.0, 0.01, 0.02));
  StateCov P = initialCovariance();
  P.block<3, 3>(sidx::kRot, sidx::kRot) = Mat3::Identity() * 0.05 * 0.05;
  P.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * 0.1 * 0.1;
  LioConfig cfg;
  cfg.max_iterations = 10;
  const LioUpdateResult r = lidarUpdate(x, P, body, map, cfg);
  EXPECT_GT(r.matched, static_cast<int>(body.size() * 0.8));
  EXPECT_LT((x.p_world_imu - truth.p_world_imu).norm(), 0.005);
  EXPECT_LT(rotationAngle(x.R_world_imu.transpose() * truth.R_world_imu), 0.05 * M_PI / 180.0);
  // Posterior covariance shrank and stays symmetric positive definite.
  EXPECT_LT((P.block<3, 3>(sidx::kPos, sidx::kPos).trace()), 0.03 * 0.03);
  EXPECT_GT(P.ldlt().vectorD().minCoeff(), 0.0);
}

// The correction's chi-square (health.hpp's first check) against priors drawn from their own
// covariance: a chi-square of at most 6 degrees of freedom, so its mean stays below 6 and its 0.1 %
// bound (22.46) is rarely passed; a prior whose error is many of its sigmas is caught, either by the
// chi-square or, when the scan lands beyond the association's gates, by the match share.
TEST(LioUpdate, CorrectionChiSquareFollowsTheDrawnPriorAndCatchesAnOverconfidentOne) {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 0.005), unit(0, 1);
  VoxelMapConfig mc;
  VoxelMap map(mc);
  map.insert(noisyMapPoints(boxScene(rng, 20000), rng, noise));
  NavState truth;
  truth.R_world_imu = expSO3(Vec3(0.02, -0.01, 0.3));
  truth.p_world_imu = Vec3(0.4, 0.2, 0.1);
  const std::vector<BodyPoint> body = scanFrom(truth, boxScene(rng, 500), rng, noise, 2.5e-5);
  LioConfig cfg;
  cfg.max_iterations = 10;
  cfg.range_noise_m = 0.005;  // the scan's noise (the floor of the correction's covariance)
  const double rot_sigma = 0.5 * M_PI / 180.0, pos_sigma = 0.04;
  StateCov P0 = initialCovariance();
  P0.block<3, 3>(sidx::kRot, sidx::kRot) = Mat3::Identity() * rot_sigma * rot_sigma;
  P0.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * pos_sigma * pos_sigma;
  const int trials = 40;
  double sum = 0;
  int above = 0;
  for (int k = 0; k < trials; ++k) {
    NavState x = truth;
    x.R_world_imu = truth.R_world_imu * expSO3(rot_sigma * Vec3(unit(rng), unit(rng), unit(rng)));
    x.p_world_imu += pos_sigma * Vec3(unit(rng), unit(rng), unit(rng));
    StateCov P = P0;
    const LioUpdateResult r = lidarUpdate(x, P, body, map, cfg);
    ASSERT_GT(r.matched, 0.8 * double(r.covered)) << k;
    EXPECT_LT((x.p_world_imu - truth.p_world_imu).norm(), 0.01) << k;
    sum += r.correction_chi2;
    above += r.correction_chi2 > HealthConfig().correction_chi2_max;
  }
  // Measured 2026-12-07: mean 5.44 (below 6: the floor of the LiDAR's resolution), 0 of 40 above.
  EXPECT_LT(sum / trials, 8.0);
  EXPECT_LE(above, 2);
  std::printf("correction chi2 over %d drawn priors: mean %.2f, %d above the bound\n", trials, sum / trials, above);

  // The same scan with a prior 6 cm off along x and a sigma of 1 cm (the filter sure of a wrong
  // pose, the scan still within the gates): the correction's chi-square is far out.
  NavState x = truth;
  x.p_world_imu += Vec3(0.06, 0.0, 0.0);
  StateCov P = P0;
  P.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * 1e-4;
  const LioUpdateResult r = lidarUpdate(x, P, body, map, cfg);
  EXPECT_GT(r.correction_chi2, HealthConfig().correction_chi2_max) << "matched " << r.matched << " of " << r.covered;
  // 12 cm off: beyond the gates of a 1 cm prior along x. Either the x walls' third of the points stops
  // matching (the share check's case; the correction cannot see what does not match) or an iteration
  // re-associates them and pulls the pose back, and then the correction is many sigmas: which of the two
  // happens is a knife edge of the iteration (x86: 1986 of 2961 matched, 2026-12-07; the arm64 build,
  // whose compiler fuses multiply-adds, 2988 of 2998 matched, 2026-12-08). The health checks catch both.
  NavState far = truth;
  far.p_world_imu += Vec3(0.12, 0.0, 0.0);
  P = P0;
  P.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * 1e-4;
  const LioUpdateResult rf = lidarUpdate(far, P, body, map, cfg);
  const bool share_low = rf.matched < 0.8 * rf.covered;
  const bool chi2_high = rf.correction_chi2 > HealthConfig().correction_chi2_max;
  EXPECT_TRUE(share_low || chi2_high) << "matched " << rf.matched << " of " << rf.covered << ", chi2 "
                                      << rf.correction_chi2;
  std::printf("12 cm off: matched %d of %d, correction chi2 %.1f\n", rf.matched, rf.covered, rf.correction_chi2);
}

// The association runs in fixed blocks on the pool's threads and is summed in block order: the
// posterior is the same to the bit for every thread count and without a pool.
TEST(LioUpdate, SamePosteriorToTheBitForEveryThreadCount) {
  std::mt19937 rng(16);
  std::normal_distribution<double> noise(0, 0.005);
  VoxelMap map(VoxelMapConfig{});
  const std::vector<PointWithCov> mpts = noisyMapPoints(boxScene(rng, 10000), rng, noise);
  map.insert(mpts);
  NavState truth;
  truth.R_world_imu = expSO3(Vec3(0.02, 0.04, -0.3));
  // 9000 points: 36 association blocks.
  const std::vector<BodyPoint> body = scanFrom(truth, boxScene(rng, 1500), rng, noise, 2.5e-5);
  NavState x0 = truth;
  x0.p_world_imu += Vec3(0.04, 0.03, -0.02);
  x0.R_world_imu = truth.R_world_imu * expSO3(Vec3(0.01, -0.01, 0.015));
  StateCov P0 = initialCovariance();
  P0.block<3, 3>(sidx::kRot, sidx::kRot) = Mat3::Identity() * 0.05 * 0.05;
  P0.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * 0.1 * 0.1;
  LioConfig cfg;
  cfg.max_iterations = 8;
  NavState x_ref = x0;
  StateCov P_ref = P0;
  const LioUpdateResult r_ref = lidarUpdate(x_ref, P_ref, body, map, cfg);
  ASSERT_GT(r_ref.matched, 7000);
  ASSERT_GT(r_ref.iterations, 1);
  for (int threads : {1, 2, 3, 4}) {
    WorkerPool pool(threads);
    NavState x = x0;
    StateCov P = P0;
    const LioUpdateResult r = lidarUpdate(x, P, body, map, cfg, &pool);
    EXPECT_EQ(r.iterations, r_ref.iterations) << threads;
    EXPECT_EQ(r.matched_index, r_ref.matched_index) << threads;
    EXPECT_EQ(r.rms_residual_m, r_ref.rms_residual_m) << threads;
    EXPECT_TRUE(x.p_world_imu == x_ref.p_world_imu) << threads << ": " << (x.p_world_imu - x_ref.p_world_imu).transpose();
    EXPECT_TRUE(x.R_world_imu == x_ref.R_world_imu) << threads;
    EXPECT_TRUE(P == P_ref) << threads << ": max |dP| " << (P - P_ref).cwiseAbs().maxCoeff();
  }
}

// With a weak prior the iterated update is Gauss-Newton on the point-to-plane cost: compare with a
// batch Gauss-Newton solution computed independently on the same associations.
TEST(LioUpdate, MatchesBatchGaussNewtonWithWeakPrior) {
  std::mt19937 rng(7);
  VoxelMap map(VoxelMapConfig{});
  std::vector<PointWithCov> mpts;
  for (const auto& p : boxScene(rng, 20000)) {
    PointWithCov pw;
    pw.p_world = p;
    pw.cov_world = Mat3::Identity() * 1e-6;
    mpts.push_back(pw);
  }
  map.insert(mpts);
  NavState truth;
  truth.R_world_imu = expSO3(Vec3(0.0, 0.0, 0.2));
  std::normal_distribution<double> noise(0, 0.01);
  const std::vector<BodyPoint> body = scanFrom(truth, boxScene(rng, 300), rng, noise, 1e-4);
  NavState x = truth;
  x.p_world_imu += Vec3(0.02, 0.01, -0.01);
  // A prior far weaker than the ~1800 residuals (information 400 vs ~1e7 per axis), yet wide enough
  // for the uncertainty-aware association gates.
  StateCov P = initialCovariance();
  P.block<3, 3>(sidx::kRot, sidx::kRot) = Mat3::Identity() * 0.02 * 0.02;
  P.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * 0.05 * 0.05;
  LioConfig cfg;
  cfg.max_iterations = 20;
  cfg.residual_floor_var = 0.0;
  NavState x_filter = x;
  const LioUpdateResult fr = lidarUpdate(x_filter, P, body, map, cfg);
  EXPECT_TRUE(fr.converged);

  // Batch Gauss-Newton on [dtheta, dp], re-associating at every step with the same gates as the filter
  // (prior-based world covariance for association, the point's own noise for the weights).
  NavState y = x;
  for (int it = 0; it < 10; ++it) {
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    for (const auto& bp : body) {
      PointWithCov pw;
      pw.p_world = y.R_world_imu * bp.p_imu + y.p_world_imu;
      pw.cov_world = worldPointCovariance(y, P, bp);  // the filter's last gates used its posterior
      VoxelMap::PlaneMatch m;
      if (!map.findBestPlane(pw, m)) continue;
      const PlaneResidual r = planeResidual(y, bp.p_imu, m.plane->normal, m.plane->d);
      const double w = 1.0 / pointToPlaneVariance(*m.plane, pw.p_world, x.R_world_imu * bp.cov_imu * x.R_world_imu.transpose());
      A += w * r.h * r.h.transpose();
      b += w * r.h * r.residual;
    }
    const Eigen::Matrix<double, 6, 1> step = -A.ldlt().solve(b);
    StateVec d = StateVec::Zero();
    d.head<6>() = step;
    y = y.boxplus(d);
  }
  EXPECT_LT((y.p_world_imu - x_filter.p_world_imu).norm(), 2e-4);
  // Both stop at the convergence threshold (0.01 deg per step): agreement to a fraction of it.
  EXPECT_LT(rotationAngle(y.R_world_imu.transpose() * x_filter.R_world_imu), 5e-5);
  EXPECT_LT((x_filter.p_world_imu - truth.p_world_imu).norm(), 0.005);
}

namespace {

// A corridor (walls, floor and ceiling along x, nothing across it): the LiDAR constrains y and z only.
std::vector<Vec3> corridorScene(std::mt19937& rng, int per_face) {
  std::uniform_real_distribution<double> along(-12.0, 12.0), u(0.0, 1.0);
  std::vector<Vec3> pts;
  for (int i = 0; i < per_face; ++i) {
    pts.emplace_back(along(rng), -1.5, 2.5 * u(rng));
    pts.emplace_back(along(rng), 1.5, 2.5 * u(rng));
    pts.emplace_back(along(rng), 3.0 * u(rng) - 1.5, 0.0);
    pts.emplace_back(along(rng), 3.0 * u(rng) - 1.5, 2.5);
  }
  return pts;
}

}  // namespace

// Along a direction the planes do not constrain (a corridor's axis) the update neither measures nor
// moves the position and velocity when the prior is far wider there than across (a start, a long
// wall): a prior whose wide axis is tilted 2.3 deg from the corridor's (an earlier frame's free
// direction) would otherwise turn the floor's 3 cm correction into 0.75 m along the axis. With a
// round prior the same scene leaves the axis where the IMU's correlations put it.
TEST(LioUpdate, FreeDirectionNotMovedThroughAWidePriorsCorrelation) {
  std::mt19937 rng(23);
  std::normal_distribution<double> noise(0, 0.005);
  VoxelMap map(VoxelMapConfig{});
  const std::vector<PointWithCov> mpts = noisyMapPoints(corridorScene(rng, 8000), rng, noise);
  map.insert(mpts);
  NavState truth;
  truth.p_world_imu = Vec3(0.0, 0.2, 1.2);
  const std::vector<BodyPoint> body = scanFrom(truth, corridorScene(rng, 600), rng, noise, 2.5e-5);

  // Prior: 1 m along e = (1, 0, 0.04) (normalised), 1 cm across, the same for the velocity (1 m/s,
  // 1 cm/s) and fully correlated with the position; 3 cm too high.
  const Vec3 e = Vec3(1.0, 0.0, 0.04).normalized();
  const Mat3 wide = e * e.transpose() * 1.0 + (Mat3::Identity() - e * e.transpose()) * 1e-4;
  StateCov P0 = initialCovariance();
  P0.block<3, 3>(sidx::kRot, sidx::kRot) = Mat3::Identity() * 1e-6;
  P0.block<3, 3>(sidx::kPos, sidx::kPos) = wide;
  P0.block<3, 3>(sidx::kVel, sidx::kVel) = wide;
  P0.block<3, 3>(sidx::kPos, sidx::kVel) = 0.99 * wide;
  P0.block<3, 3>(sidx::kVel, sidx::kPos) = 0.99 * wide;
  NavState x0 = truth;
  x0.p_world_imu.z() += 0.03;
  LioConfig cfg;
  cfg.max_iterations = 10;

  NavState x = x0;
  StateCov P = P0;
  const LioUpdateResult r = lidarUpdate(x, P, body, map, cfg);
  ASSERT_GT(r.matched, 2000);
  EXPECT_LT(std::abs(x.p_world_imu.z() - truth.p_world_imu.z()), 0.005);  // the floor's correction
  EXPECT_LT(std::abs(x.p_world_imu.x() - x0.p_world_imu.x()), 0.005);     // nothing along the axis
  EXPECT_LT(std::abs(x.v_world.x() - x0.v_world.x()), 0.005);
  // The covariance is the filtered gain's: still about 1 m along the axis, symmetric positive definite.
  EXPECT_GT(std::sqrt(e.dot(P.block<3, 3>(sidx::kPos, sidx::kPos) * e)), 0.9);
  EXPECT_LT(std::sqrt(P(sidx::kPos + 2, sidx::kPos + 2)), 0.05);
  EXPECT_GT(P.ldlt().vectorD().minCoeff(), 0.0);

  // A round prior (1 cm everywhere, position and velocity independent): the plain update, the same
  // floor correction, the axis left alone because nothing links it to z.
  StateCov P1 = initialCovariance();
  P1.block<3, 3>(sidx::kRot, sidx::kRot) = Mat3::Identity() * 1e-6;
  P1.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * 0.05 * 0.05;
  NavState x1 = x0;
  lidarUpdate(x1, P1, body, map, cfg);
  EXPECT_LT(std::abs(x1.p_world_imu.z() - truth.p_world_imu.z()), 0.005);
  EXPECT_LT(std::abs(x1.p_world_imu.x() - x0.p_world_imu.x()), 0.005);
  // No information along the axis: its variance is the prior's.
  EXPECT_NEAR(P1(sidx::kPos, sidx::kPos), 0.05 * 0.05, 1e-6);
}

TEST(Degeneracy, SigmaMinOfPlaneFamilies) {
  // Three orthogonal families, equally represented: all eigenvalues equal -> 1/sqrt(3).
  std::vector<Vec3> n;
  for (int i = 0; i < 100; ++i) {
    n.push_back(Vec3::UnitX());
    n.push_back(Vec3::UnitY());
    n.push_back(-Vec3::UnitZ());
  }
  EXPECT_NEAR(degeneracySigmaMin(n), 1.0 / std::sqrt(3.0), 1e-12);
  // The selector's factor sqrt(3) sigma_min maps this best case to 1 (thresholds = tau_predef).
  EXPECT_NEAR(std::sqrt(3.0) * degeneracySigmaMin(n), 1.0, 1e-12);
  // Parallel planes (a corridor floor seen alone, or one wall): degenerate.
  std::vector<Vec3> wall(200, Vec3::UnitX());
  EXPECT_NEAR(degeneracySigmaMin(wall), 0.0, 1e-12);
  // Corridor: two walls and floor/ceiling, nothing along the axis x.
  std::vector<Vec3> corridor;
  for (int i = 0; i < 100; ++i) {
    corridor.push_back(Vec3::UnitY());
    corridor.push_back(Vec3::UnitZ());
  }
  EXPECT_NEAR(degeneracySigmaMin(corridor), 0.0, 1e-12);
  EXPECT_EQ(degeneracySigmaMin({}), 0.0);
  // Unequal families: 10 % of the normals along x, 30 % along y, 60 % along z -> sqrt(0.1).
  std::vector<Vec3> mixed;
  for (int i = 0; i < 10; ++i) {
    mixed.push_back(Vec3::UnitX());
    for (int k = 0; k < 3; ++k) mixed.push_back(-Vec3::UnitY());
    for (int k = 0; k < 6; ++k) mixed.push_back(Vec3::UnitZ());
  }
  EXPECT_NEAR(degeneracySigmaMin(mixed), std::sqrt(0.1), 1e-12);
  // Invariant to the normals' signs and to a rotation of the scene.
  const Mat3 R = expSO3(Vec3(0.3, -1.1, 0.7));
  std::vector<Vec3> rotated;
  for (std::size_t i = 0; i < mixed.size(); ++i) rotated.push_back((i % 2 ? -1.0 : 1.0) * (R * mixed[i]));
  EXPECT_NEAR(degeneracySigmaMin(rotated), std::sqrt(0.1), 1e-9);
}

// Real LiDAR: each KITTI sequence 07 scan registered to a map of the previous ones (stored poses),
// starting 0.3 m / 2 deg off, must land within 5 cm / 0.2 deg of its stored pose, and within 1 cm /
// 0.02 deg of where the same registration lands when started at the stored pose (the basin of
// convergence covers the perturbation). The stored poses are themselves an estimate: scan 4's
// registration optimum lies ~5 cm from it whatever the start.
TEST(LioUpdate, KittiScansRegisterToMapOfPreviousScans) {
  const std::string dir = std::string(LIVO_SHARED_DATA) + "/kitti_newer_college_scans/kitti_07_dump";
  if (!std::filesystem::exists(dir)) LIVO_SKIP() << "no reference data at " << dir;
  std::vector<Pose> poses;
  {
    std::ifstream g(dir + "/graph.txt");
    std::string name;
    double v[7];
    while (g >> name >> v[0] >> v[1] >> v[2] >> v[3] >> v[4] >> v[5] >> v[6]) poses.push_back(poseFromArray(v));
  }
  ASSERT_EQ(poses.size(), 5u);
  auto loadScan = [&](int i) {
    char path[256];
    std::snprintf(path, sizeof(path), "%s/%06d/points.bin", dir.c_str(), i);
    std::vector<Vec3> pts;
    std::ifstream f2(path, std::ios::binary);
    const auto n = std::filesystem::file_size(path) / (3 * sizeof(float));
    std::vector<float> xyz(n * 3);
    f2.read(reinterpret_cast<char*>(xyz.data()), static_cast<std::streamsize>(n * 3 * sizeof(float)));
    for (std::size_t k = 0; k < n; ++k) pts.emplace_back(xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
    return pts;
  };
  VoxelMapConfig mc;
  mc.voxel_size_m = 2.0;     // KITTI dump scans are sparse: 0.5 m voxels hold ~2 points each
  mc.min_eigen_value = 0.05;  // 2 m cells of outdoor surfaces (road, walls, vegetation edges)
  VoxelMap map(mc);
  LioConfig cfg;
  cfg.max_iterations = 50;
  auto toWorld = [&](const std::vector<Vec3>& pts, const Pose& T) {
    std::vector<PointWithCov> w;
    for (const auto& p : pts) {
      PointWithCov pw;
      pw.p_world = T * p;
      pw.cov_world = T.linear() * pointCovarianceBody(p, 0.02, 0.05) * T.linear().transpose();
      w.push_back(pw);
    }
    return w;
  };
  map.insert(toWorld(loadScan(0), poses[0]));
  std::mt19937 rng(8);
  for (int i = 1; i < 5; ++i) {
    const auto scan = loadScan(i);
    std::vector<BodyPoint> body;
    for (std::size_t k = 0; k < scan.size(); ++k) {
      BodyPoint bp;
      bp.p_imu = scan[k];
      bp.cov_imu = pointCovarianceBody(scan[k], 0.02, 0.05);
      body.push_back(bp);
    }
    const Pose& T_stored = poses[static_cast<std::size_t>(i)];
    auto registerFrom = [&](const Vec3& dp, const Vec3& dr, LioUpdateResult& r) {
      NavState x;
      x.R_world_imu = T_stored.linear() * expSO3(dr);
      x.p_world_imu = T_stored.translation() + dp;
      StateCov P = initialCovariance();
      P.block<3, 3>(sidx::kRot, sidx::kRot) = Mat3::Identity() * std::pow(2.0 * M_PI / 180.0, 2);
      P.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * 0.3 * 0.3;
      r = lidarUpdate(x, P, body, map, cfg);
      return x;
    };
    // Start 0.3 m and 2 deg away from the stored pose, in a random direction.
    std::normal_distribution<double> n(0, 1);
    const Vec3 dp = Vec3(n(rng), n(rng), n(rng)).normalized() * 0.3;
    const Vec3 dr = Vec3(n(rng), n(rng), n(rng)).normalized() * (2.0 * M_PI / 180.0);
    LioUpdateResult r, r0;
    const NavState x = registerFrom(dp, dr, r);
    const NavState x0 = registerFrom(Vec3::Zero(), Vec3::Zero(), r0);
    const double pos_err = (x.p_world_imu - T_stored.translation()).norm();
    const double rot_err_deg = rotationAngle(x.R_world_imu.transpose() * T_stored.linear()) * 180.0 / M_PI;
    const double basin_pos = (x.p_world_imu - x0.p_world_imu).norm();
    const double basin_rot_deg = rotationAngle(x.R_world_imu.transpose() * x0.R_world_imu) * 180.0 / M_PI;
    std::cout << "scan " << i << ": matched " << r.matched << "/" << body.size() << " in " << r.iterations
              << " iterations, error " << pos_err * 100 << " cm, " << rot_err_deg << " deg; from the stored pose "
              << (x0.p_world_imu - T_stored.translation()).norm() * 100 << " cm\n";
    EXPECT_TRUE(r.converged) << "scan " << i;
    EXPECT_LT(pos_err, 0.05) << "scan " << i;
    EXPECT_LT(rot_err_deg, 0.2) << "scan " << i;
    EXPECT_LT(basin_pos, 0.01) << "scan " << i;
    EXPECT_LT(basin_rot_deg, 0.02) << "scan " << i;
    map.insert(toWorld(scan, poses[static_cast<std::size_t>(i)]));
  }
}
