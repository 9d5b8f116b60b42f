#include "livo/map/plane.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace livo {
namespace {

const Vec3& positionOf(const PointWithCov& p) { return p.p_world; }
const Vec3& positionOf(const MapPoint& p) { return p.p_world; }
const Mat3& covOf(const PointWithCov& p) { return p.cov_world; }
Mat3 covOf(const MapPoint& p) { return p.cov(); }

template <class Point>
bool fitPlaneImpl(const std::vector<Point>& points, double min_eigen_value, Plane& out) {
  out.is_plane = false;
  const int n_pts = static_cast<int>(points.size());
  out.num_points = n_pts;
  if (n_pts < 3) return false;
  const double inv_n = 1.0 / n_pts;

  // q = mean, C = mean of centred outer products (two passes: no cancellation at large coordinates).
  Vec3 q = Vec3::Zero();
  for (const auto& pt : points) q += positionOf(pt);
  q *= inv_n;
  Mat3 C = Mat3::Zero();
  for (const auto& pt : points) {
    const Vec3 e = positionOf(pt) - q;
    C.noalias() += e * e.transpose();
  }
  C *= inv_n;

  Eigen::SelfAdjointEigenSolver<Mat3> es(C);
  const Vec3 lambda = es.eigenvalues();  // ascending
  const Mat3 U = es.eigenvectors();
  const Vec3 n = U.col(0);

  out.center = q;
  out.normal = n;
  out.d = -n.dot(q);
  out.eig_min = lambda(0);
  out.eig_mid = lambda(1);
  out.eig_max = lambda(2);
  out.radius = std::sqrt(std::max(lambda(2), 0.0));

  // Gaps lambda_min - lambda_m (m = 1, 2). A vanishing gap leaves the normal undefined.
  const double gap1 = lambda(0) - lambda(1);
  const double gap2 = lambda(0) - lambda(2);
  const double tiny = 1e-14 + 1e-12 * std::abs(lambda(2));
  const bool normal_defined = -gap1 > tiny;
  out.is_plane = lambda(0) < min_eigen_value && normal_defined;

  // Sigma_nq = sum_i J_i Sigma_i J_i^T with J_i = [U F_i; I/N]. Rows 1, 2 of F_i are
  // (p_i - q)^T M_m / (N gap_m) with M_m = u_m u0^T + u0 u_m^T (row 0 is zero), so
  // d n / d p_i = U F_i = u1 f1^T + u2 f2^T with f_m = c_m M_m e = c_m ((u0.e) u_m + (u_m.e) u0).
  // Then A Sigma A^T = sum_{m,k} (f_m^T Sigma f_k) u_m u_k^T and A Sigma = sum_m u_m (Sigma f_m)^T:
  // three scalars and two vectors per point instead of three 3x3 products (the map server refits
  // voxels with this on every update; docs/algorithms.md section 3).
  const Vec3 u0 = U.col(0), u1 = U.col(1), u2 = U.col(2);
  const double c1 = normal_defined ? inv_n / gap1 : 0.0;
  const double c2 = normal_defined && -gap2 > tiny ? inv_n / gap2 : 0.0;
  double g11 = 0.0, g12 = 0.0, g22 = 0.0;
  Vec3 h1 = Vec3::Zero(), h2 = Vec3::Zero();
  Mat3 S_qq = Mat3::Zero();
  for (const auto& pt : points) {
    const Vec3 e = positionOf(pt) - q;
    const double a0 = u0.dot(e);
    const Vec3 f1 = c1 * (a0 * u1 + u1.dot(e) * u0);
    const Vec3 f2 = c2 * (a0 * u2 + u2.dot(e) * u0);
    const Mat3 cov = covOf(pt);
    const Vec3 k1 = cov * f1, k2 = cov * f2;
    g11 += f1.dot(k1);
    g12 += f1.dot(k2);
    g22 += f2.dot(k2);
    h1 += k1;
    h2 += k2;
    S_qq += cov;
  }
  const Mat3 S_nn = g11 * (u1 * u1.transpose()) + g12 * (u1 * u2.transpose() + u2 * u1.transpose()) +
                    g22 * (u2 * u2.transpose());
  const Mat3 S_nq = u1 * h1.transpose() + u2 * h2.transpose();
  out.cov_nq.block<3, 3>(0, 0) = S_nn;
  out.cov_nq.block<3, 3>(0, 3) = S_nq * inv_n;
  out.cov_nq.block<3, 3>(3, 0) = (S_nq * inv_n).transpose();
  out.cov_nq.block<3, 3>(3, 3) = S_qq * (inv_n * inv_n);
  return out.is_plane;
}

}  // namespace

bool fitPlane(const std::vector<PointWithCov>& points, double min_eigen_value, Plane& out) {
  return fitPlaneImpl(points, min_eigen_value, out);
}

bool fitPlane(const std::vector<MapPoint>& points, double min_eigen_value, Plane& out) {
  return fitPlaneImpl(points, min_eigen_value, out);
}

double pointToPlaneVariance(const Plane& plane, const Vec3& p, const Mat3& cov_p) {
  Vec6 J;
  J << p - plane.center, -plane.normal;
  return J.dot(plane.cov_nq * J) + plane.normal.dot(cov_p * plane.normal);
}

}  // namespace livo
