// LiDAR point covariance (docs/algorithms.md section 2) and the point types the voxel map uses.
#pragma once

#include "livo/common/so3.hpp"

#include <array>

namespace livo {

/// Covariance of a LiDAR return in the sensor (body) frame from range and bearing noise:
///   Sigma_b = sigma_r^2 d d^T + A diag(sin^2 sigma_theta, sin^2 sigma_theta) A^T,  A = r [d]x N,
/// with r = |p|, d = p / r and N a 3x2 orthonormal basis of the plane normal to d. Since [d]x N is
/// again an orthonormal basis of that plane, A diag(s^2, s^2) A^T = r^2 s^2 (I - d d^T), which is what
/// is evaluated. `bearing_sigma_deg` is in DEGREES (FAST-LIVO2 beam_err). A point at the origin gets
/// sigma_r^2 I (no bearing is defined).
Mat3 pointCovarianceBody(const Vec3& p_body, double range_sigma_m, double bearing_sigma_deg);

/// A point in the world frame with its 3x3 covariance (m^2): the map's input and query type.
struct PointWithCov {
  Vec3 p_world = Vec3::Zero();
  Mat3 cov_world = Mat3::Zero();
};

/// Compact stored form (48 bytes instead of 96): position in double, the 6 distinct covariance
/// entries in float (xx, xy, xz, yy, yz, zz). Float keeps ~7 significant digits of variances that
/// are themselves uncertain by tens of percent.
struct MapPoint {
  Vec3 p_world = Vec3::Zero();
  std::array<float, 6> cov_upper{};

  MapPoint() = default;
  explicit MapPoint(const PointWithCov& pw);
  Mat3 cov() const;
};

}  // namespace livo
