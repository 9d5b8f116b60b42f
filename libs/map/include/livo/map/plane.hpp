// Plane fit with uncertainty (docs/algorithms.md section 3, "Plane fit" and "Plane uncertainty").
#pragma once

#include "livo/map/point_cov.hpp"

#include <vector>

namespace livo {

struct Plane {
  Vec3 center = Vec3::Zero();  ///< q: mean of the points, world frame, m
  Vec3 normal = Vec3::UnitZ(); ///< n: unit eigenvector of the smallest eigenvalue (sign arbitrary)
  double d = 0.0;              ///< plane offset: n^T p + d = 0, d = -n^T q
  Mat6 cov_nq = Mat6::Zero();  ///< covariance of [n; q] (order normal, centre), m^2 for the q block
  double radius = 0.0;         ///< sqrt(lambda_max), m: the in-plane extent used by the association gate
  double eig_min = 0.0, eig_mid = 0.0, eig_max = 0.0;  ///< eigenvalues of the scatter matrix, m^2
  int num_points = 0;          ///< points used in the last fit
  int layer = 0;               ///< octree layer of the node holding the plane (set by VoxelMap)
  bool is_plane = false;       ///< eig_min < min_eigen_value (and a well-defined normal)

  /// Signed distance n^T p + d.
  double signedDistance(const Vec3& p) const { return normal.dot(p) + d; }
};

/// Fits a plane to the points (at least 3) and propagates their covariances to Sigma_nq:
///   q = mean(p_i), C = mean((p_i - q)(p_i - q)^T) (two-pass, accurate far from the origin),
///   C = U diag(lambda) U^T with Eigen::SelfAdjointEigenSolver (ascending), n = u_min,
///   Sigma_nq = sum_i J_i Sigma_i J_i^T, J_i = [U F_i; I/N], where row m != min of F_i is
///   (p_i - q)^T (u_m u_min^T + u_min u_m^T) / (N (lambda_min - lambda_m)) and row min is 0
///   (first-order eigenvector perturbation). Returns out.is_plane: lambda_min < min_eigen_value and
///   the smallest eigenvalue is separated from the middle one (else the normal is undefined).
/// Fewer than 3 points: returns false and leaves out.is_plane = false.
bool fitPlane(const std::vector<PointWithCov>& points, double min_eigen_value, Plane& out);
/// The same on the map's compact stored points.
bool fitPlane(const std::vector<MapPoint>& points, double min_eigen_value, Plane& out);

/// Variance of the point-to-plane distance n^T p + d (docs/algorithms.md section 2):
///   sigma_l = J Sigma_nq J^T + n^T Sigma_p n,  J = [(p - q)^T, -n^T].
double pointToPlaneVariance(const Plane& plane, const Vec3& p, const Mat3& cov_p);

}  // namespace livo
