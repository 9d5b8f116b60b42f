// libs/map: point covariance and plane fit (normal, centre, covariance) against Monte-Carlo sampling.
#include "map_test_util.hpp"

#include "livo/map/plane.hpp"
#include "livo/map/point_cov.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <iostream>
#include <random>
#include <vector>

using namespace livo;
using namespace livo::test;

// ---------------------------------------------------------------- point covariance
TEST(PointCov, BodyCovarianceMatchesMonteCarlo) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double sigma_r = 0.03;
  for (double sigma_deg : {0.05, 0.5, 2.0}) {
    for (double range : {1.0, 7.0, 40.0}) {
      const Vec3 d = randomUnit(rng);
      const Vec3 p = range * d;
      const Mat3 analytic = pointCovarianceBody(p, sigma_r, sigma_deg);
      // Oracle: perturb the range and two bearing angles (about two axes normal to d).
      Vec3 t1, t2;
      tangentBasis(d, t1, t2);
      const double sigma_rad = sigma_deg * M_PI / 180.0;
      std::vector<Vec3> samples;
      for (int k = 0; k < 40000; ++k) {
        const double r = range + sigma_r * n01(rng);
        const Vec3 phi = sigma_rad * (n01(rng) * t1 + n01(rng) * t2);
        samples.push_back(r * (expSO3(phi) * d));
      }
      const Mat3 mc = empiricalCov<3>(samples);
      EXPECT_LT((mc - analytic).norm() / analytic.norm(), 0.04) << "deg " << sigma_deg << " r " << range;
      // Per direction: radial variance sigma_r^2, tangential r^2 sin^2(sigma_theta) (degrees!).
      EXPECT_NEAR(d.dot(analytic * d), sigma_r * sigma_r, 1e-12);
      const double s = std::sin(sigma_rad);
      EXPECT_NEAR(t1.dot(analytic * t1) / (range * range * s * s), 1.0, 1e-9);
      EXPECT_NEAR(t2.dot(mc * t2) / t2.dot(analytic * t2), 1.0, 0.04);
    }
  }
  EXPECT_TRUE(pointCovarianceBody(Vec3::Zero(), 0.02, 0.05).isApprox(0.0004 * Mat3::Identity()));
}

TEST(PointCov, CompactStorageKeepsTheCovariance) {
  const PointWithCov pw = withCov(Vec3(-3.2, 4.1, 0.7), Vec3::Zero());
  const MapPoint mp(pw);
  EXPECT_EQ(sizeof(MapPoint), 48u);
  EXPECT_EQ(mp.p_world, pw.p_world);
  EXPECT_LT((mp.cov() - pw.cov_world).norm() / pw.cov_world.norm(), 1e-6);
}

// ---------------------------------------------------------------- plane fit
TEST(PlaneFit, RecoversKnownPlaneFarFromOrigin) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (const Vec3& offset : {Vec3(0.1, -0.2, 0.3), Vec3(-1e5, 2e5, -3e4)}) {
    const Vec3 n_true = randomUnit(rng);
    Vec3 t1, t2;
    tangentBasis(n_true, t1, t2);
    const double sigma_n = 0.003;  // noise along the normal, m
    std::vector<PointWithCov> pts;
    for (int i = 0; i < 300; ++i) {
      PointWithCov pw;
      pw.p_world = offset + u(rng) * t1 + u(rng) * t2 + sigma_n * std::normal_distribution<double>()(rng) * n_true;
      pw.cov_world = sigma_n * sigma_n * Mat3::Identity();
      pts.push_back(pw);
    }
    Plane plane;
    ASSERT_TRUE(fitPlane(pts, 0.0025, plane));
    EXPECT_GT(std::abs(plane.normal.dot(n_true)), 0.999);
    EXPECT_LT(std::abs(n_true.dot(plane.center - offset)), 1e-3);  // centre on the true plane
    EXPECT_NEAR(plane.eig_min, sigma_n * sigma_n, 0.3 * sigma_n * sigma_n);
    EXPECT_NEAR(plane.eig_max, 0.36 / 12.0, 0.005);  // uniform on 0.6 m: 0.6^2 / 12
    EXPECT_NEAR(plane.radius, std::sqrt(plane.eig_max), 1e-12);
    EXPECT_NEAR(plane.signedDistance(plane.center), 0.0, 1e-9);
    EXPECT_EQ(plane.num_points, 300);
  }
  // A volume, a line and two points are not planes.
  std::vector<PointWithCov> blob, line, two;
  for (int i = 0; i < 50; ++i) {
    blob.push_back(withCov(Vec3(u(rng), u(rng), u(rng)), Vec3(5, 0, 0)));
    line.push_back(withCov(Vec3(0.01 * i, 0.02 * i, -0.01 * i), Vec3(5, 0, 0)));
  }
  two.assign(line.begin(), line.begin() + 2);
  Plane p;
  EXPECT_FALSE(fitPlane(blob, 0.0025, p));
  EXPECT_FALSE(fitPlane(line, 0.0025, p));
  EXPECT_FALSE(fitPlane(two, 0.0025, p));
}

// Sigma_nq against the explicit first-order formula, J_i = [U F_i; I/N] formed as 6x3 matrices and
// sum_i J_i Sigma_i J_i^T summed directly (fitPlane sums the same terms without forming F_i), on planes
// far from the origin, tilted, with anisotropic point covariances, and on a nearly isotropic blob.
TEST(PlaneFit, CovarianceEqualsTheExplicitJacobianSum) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.25, 0.25);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 centre(100.0 * u(rng), -300.0 * u(rng), 10.0 * u(rng));
    const Vec3 n_true = Vec3(u(rng), u(rng), 1.0).normalized();
    Vec3 t1, t2;
    tangentBasis(n_true, t1, t2);
    const double thickness = trial % 10 == 9 ? 0.25 : 0.01;  // every tenth: not planar
    std::vector<PointWithCov> pts;
    const int n_pts = 6 + trial;
    for (int i = 0; i < n_pts; ++i) {
      const Vec3 p = centre + u(rng) * t1 + 0.6 * u(rng) * t2 + thickness * u(rng) * n_true;
      pts.push_back(withCov(p, centre + Vec3(3.0, -2.0, 1.5), 0.02, 0.2));
    }
    Plane fit;
    fitPlane(pts, 0.0025, fit);
    // The oracle, from the eigen-decomposition of the same scatter.
    const double N = double(n_pts);
    Vec3 q = Vec3::Zero();
    for (const auto& p : pts) q += p.p_world;
    q /= N;
    Mat3 C = Mat3::Zero();
    for (const auto& p : pts) C += (p.p_world - q) * (p.p_world - q).transpose();
    C /= N;
    Eigen::SelfAdjointEigenSolver<Mat3> es(C);
    const Vec3 lam = es.eigenvalues();
    Mat3 U = es.eigenvectors();
    if (U.col(0).dot(fit.normal) < 0) U.col(0) = -U.col(0);  // eigenvector signs are arbitrary
    Eigen::Matrix<double, 6, 6> ref = Eigen::Matrix<double, 6, 6>::Zero();
    for (const auto& p : pts) {
      Mat3 F = Mat3::Zero();
      for (int m = 1; m < 3; ++m) {
        const Mat3 M = U.col(m) * U.col(0).transpose() + U.col(0) * U.col(m).transpose();
        F.row(m) = (p.p_world - q).transpose() * M / (N * (lam(0) - lam(m)));
      }
      Eigen::Matrix<double, 6, 3> J;
      J.topRows<3>() = U * F;
      J.bottomRows<3>() = Mat3::Identity() / N;
      ref += J * p.cov_world * J.transpose();
    }
    EXPECT_LT((fit.cov_nq - ref).norm(), 1e-9 * ref.norm()) << "trial " << trial << "\n" << fit.cov_nq << "\n" << ref;
    EXPECT_LT((fit.cov_nq - fit.cov_nq.transpose()).norm(), 1e-12 * ref.norm()) << "trial " << trial;
  }
}

// Sigma_nq against the spread of [n; q] over re-sampled point sets. The normal has no variance along
// itself (unit length), so the comparison uses the 5 meaningful directions: the two tangent
// components of n and the three of q.
TEST(PlaneFit, CovarianceMatchesMonteCarlo) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.25, 0.25);
  const Vec3 sensor(4.0, -3.0, 2.0);
  const Vec3 n_true = Vec3(0.2, -0.1, 1.0).normalized();
  Vec3 t1, t2;
  tangentBasis(n_true, t1, t2);
  std::vector<PointWithCov> nominal;
  for (int i = 0; i < 30; ++i) {
    const Vec3 p = Vec3(-1.0, 2.0, 0.5) + u(rng) * t1 + u(rng) * t2;
    const PointWithCov pw = withCov(p, sensor, 0.01, 0.3);
    nominal.push_back(PointWithCov{sampleGaussian(p, pw.cov_world, rng), pw.cov_world});
  }
  Plane ref;
  ASSERT_TRUE(fitPlane(nominal, 0.0025, ref));

  Eigen::Matrix<double, 5, 6> T = Eigen::Matrix<double, 5, 6>::Zero();
  Vec3 u1, u2;
  tangentBasis(ref.normal, u1, u2);
  T.block<1, 3>(0, 0) = u1.transpose();
  T.block<1, 3>(1, 0) = u2.transpose();
  T.block<3, 3>(2, 3) = Mat3::Identity();

  const Vec3 probe = ref.center + 0.2 * u1 - 0.1 * u2 + 0.01 * ref.normal;
  std::vector<Eigen::Matrix<double, 5, 1>> proj;
  std::vector<Eigen::Matrix<double, 1, 1>> dist;
  std::vector<PointWithCov> resampled = nominal;
  for (int k = 0; k < 5000; ++k) {
    for (std::size_t i = 0; i < nominal.size(); ++i)
      resampled[i].p_world = sampleGaussian(nominal[i].p_world, nominal[i].cov_world, rng);
    Plane fit;
    fitPlane(resampled, 0.0025, fit);
    if (fit.normal.dot(ref.normal) < 0) fit.normal = -fit.normal;  // eigenvector sign is arbitrary
    Vec6 nq;
    nq << fit.normal, fit.center;
    proj.push_back(T * nq);
    Eigen::Matrix<double, 1, 1> dd;
    dd << fit.normal.dot(probe - fit.center);
    dist.push_back(dd);
  }
  const Eigen::Matrix<double, 5, 5> mc = empiricalCov<5>(proj);
  const Eigen::Matrix<double, 5, 5> analytic = T * ref.cov_nq * T.transpose();
  EXPECT_LT((mc - analytic).norm() / analytic.norm(), 0.15) << "MC\n" << mc << "\nanalytic\n" << analytic;
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(mc(i, i) / analytic(i, i), 1.0, 0.2) << "direction " << i;
  }
  std::cout << "[plane] MC vs analytic: rel. Frobenius " << (mc - analytic).norm() / analytic.norm()
            << ", variance ratios " << (mc.diagonal().array() / analytic.diagonal().array()).transpose() << "\n";
  // The normal block has (numerically) no component along the normal itself.
  EXPECT_LT((ref.cov_nq.block<3, 3>(0, 0) * ref.normal).norm(), 1e-9 * ref.cov_nq.norm());
  // Distance variance of a probe point with an exact position: J Sigma_nq J^T.
  const double sigma_l = pointToPlaneVariance(ref, probe, Mat3::Zero());
  EXPECT_NEAR(empiricalCov<1>(dist)(0, 0) / sigma_l, 1.0, 0.15);
  std::cout << "[plane] distance variance MC / sigma_l " << empiricalCov<1>(dist)(0, 0) / sigma_l << "\n";
}
