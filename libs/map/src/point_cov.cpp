#include "livo/map/point_cov.hpp"

#include <cmath>

namespace livo {

Mat3 pointCovarianceBody(const Vec3& p_body, double range_sigma_m, double bearing_sigma_deg) {
  const double r = p_body.norm();
  const double var_r = range_sigma_m * range_sigma_m;
  if (!(r > 1e-9)) return var_r * Mat3::Identity();
  const Vec3 d = p_body / r;
  const Mat3 ddT = d * d.transpose();
  // sin^2(sigma_theta) with sigma_theta converted from degrees (docs/algorithms.md section 2).
  const double s = std::sin(bearing_sigma_deg * M_PI / 180.0);
  const double var_tangent = r * r * s * s;  // r^2 sin^2(sigma_theta): A diag(.) A^T = this * (I - ddT)
  return var_r * ddT + var_tangent * (Mat3::Identity() - ddT);
}

MapPoint::MapPoint(const PointWithCov& pw) : p_world(pw.p_world) {
  const Mat3& c = pw.cov_world;
  // Symmetrise while compressing: the upper triangle takes the mean of both off-diagonal entries.
  cov_upper = {static_cast<float>(c(0, 0)), static_cast<float>(0.5 * (c(0, 1) + c(1, 0))),
               static_cast<float>(0.5 * (c(0, 2) + c(2, 0))), static_cast<float>(c(1, 1)),
               static_cast<float>(0.5 * (c(1, 2) + c(2, 1))), static_cast<float>(c(2, 2))};
}

Mat3 MapPoint::cov() const {
  const auto& u = cov_upper;
  Mat3 c;
  c << u[0], u[1], u[2],  //
      u[1], u[3], u[4],   //
      u[2], u[4], u[5];
  return c;
}

}  // namespace livo
