// Shared helpers of the libs/map tests (tests/test_map_*.cpp): random directions and tangent bases,
// Gaussian samples and empirical covariances (Monte-Carlo oracles), points with a range/bearing covariance.
#pragma once

#include "livo/map/point_cov.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <random>
#include <vector>

namespace livo::test {

inline Vec3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

// Two unit vectors completing `n` to an orthonormal basis.
inline void tangentBasis(const Vec3& n, Vec3& t1, Vec3& t2) {
  t1 = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
  t2 = n.cross(t1);
}

// Draws one sample of N(mean, cov).
inline Vec3 sampleGaussian(const Vec3& mean, const Mat3& cov, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::LLT<Mat3> llt(cov);
  return mean + llt.matrixL() * Vec3(n(rng), n(rng), n(rng));
}

template <int D>
inline Eigen::Matrix<double, D, D> empiricalCov(const std::vector<Eigen::Matrix<double, D, 1>>& xs) {
  Eigen::Matrix<double, D, 1> mean = Eigen::Matrix<double, D, 1>::Zero();
  for (const auto& x : xs) mean += x;
  mean /= static_cast<double>(xs.size());
  Eigen::Matrix<double, D, D> c = Eigen::Matrix<double, D, D>::Zero();
  for (const auto& x : xs) c += (x - mean) * (x - mean).transpose();
  return c / static_cast<double>(xs.size() - 1);
}

// A world point with the covariance of a return seen from `sensor` (world = body orientation).
inline PointWithCov withCov(const Vec3& p, const Vec3& sensor, double sigma_r = 0.02, double sigma_deg = 0.1) {
  PointWithCov pw;
  pw.p_world = p;
  pw.cov_world = pointCovarianceBody(p - sensor, sigma_r, sigma_deg);
  return pw;
}

}  // namespace livo::test
