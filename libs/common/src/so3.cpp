#include "livo/common/so3.hpp"

#include <cmath>
#include <stdexcept>

namespace livo {

Mat3 hat(const Vec3& v) {
  Mat3 m;
  m << 0.0, -v.z(), v.y(),  //
      v.z(), 0.0, -v.x(),   //
      -v.y(), v.x(), 0.0;
  return m;
}

Vec3 vee(const Mat3& m) { return Vec3(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1)) * 0.5; }

Mat3 expSO3(const Vec3& phi) {
  const double theta2 = phi.squaredNorm();
  const Mat3 K = hat(phi);
  if (theta2 < 1e-10) {
    // Taylor series to second order: I + K + K^2/2 (error O(theta^3)).
    return Mat3::Identity() + K + 0.5 * K * K;
  }
  const double theta = std::sqrt(theta2);
  return Mat3::Identity() + (std::sin(theta) / theta) * K + ((1.0 - std::cos(theta)) / theta2) * K * K;
}

Vec3 logSO3(const Mat3& R_in) {
  // Re-orthonormalise through a quaternion: robust near pi, where (R - R^T) vanishes.
  Quat q(R_in);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // angle in [0, pi]
  const Vec3 v = q.vec();
  const double s = v.norm();
  if (s < 1e-10) {
    // theta ~= 2 s, axis*theta ~= 2 v / w (w ~ 1).
    return 2.0 * v / q.w();
  }
  const double theta = 2.0 * std::atan2(s, q.w());
  return v * (theta / s);
}

Mat3 rightJacobianSO3(const Vec3& phi) {
  const double theta2 = phi.squaredNorm();
  const Mat3 K = hat(phi);
  if (theta2 < 1e-10) return Mat3::Identity() - 0.5 * K + K * K / 6.0;
  const double theta = std::sqrt(theta2);
  return Mat3::Identity() - ((1.0 - std::cos(theta)) / theta2) * K +
         ((theta - std::sin(theta)) / (theta2 * theta)) * K * K;
}

Mat3 rightJacobianInvSO3(const Vec3& phi) {
  const double theta2 = phi.squaredNorm();
  const Mat3 K = hat(phi);
  if (theta2 < 1e-10) return Mat3::Identity() + 0.5 * K + K * K / 12.0;
  const double theta = std::sqrt(theta2);
  // (1 + cos t) / (2 t sin t) written as cot(t/2) / (2 t): finite up to t = pi.
  const double c = 1.0 / theta2 - std::cos(0.5 * theta) / (2.0 * theta * std::sin(0.5 * theta));
  return Mat3::Identity() + 0.5 * K + c * K * K;
}

Mat3 leftJacobianSO3(const Vec3& phi) { return rightJacobianSO3(-phi); }

Pose expSE3(const Vec6& xi) {
  const Vec3 rho = xi.head<3>();
  const Vec3 phi = xi.tail<3>();
  Pose T = Pose::Identity();
  T.linear() = expSO3(phi);
  T.translation() = leftJacobianSO3(phi) * rho;
  return T;
}

Vec6 logSE3(const Pose& T) {
  const Vec3 phi = logSO3(T.linear());
  const double theta2 = phi.squaredNorm();
  Mat3 Jl_inv;
  if (theta2 < 1e-10) {
    const Mat3 K = hat(phi);
    Jl_inv = Mat3::Identity() - 0.5 * K + K * K / 12.0;
  } else {
    Jl_inv = rightJacobianInvSO3(-phi);
  }
  Vec6 xi;
  xi.head<3>() = Jl_inv * T.translation();
  xi.tail<3>() = phi;
  return xi;
}

Pose poseFromArray(const double* a) {
  Quat q(a[6], a[3], a[4], a[5]);
  const double n = q.norm();
  if (!(n > 1e-9) || !std::isfinite(n)) throw std::invalid_argument("pose quaternion has zero or invalid norm");
  q.coeffs() /= n;
  Pose T = Pose::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Vec3(a[0], a[1], a[2]);
  return T;
}

std::array<double, 7> poseToArray(const Pose& T) {
  Quat q(T.linear());
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // canonical sign: qw >= 0
  const Vec3 t = T.translation();
  return {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
}

double rotationAngle(const Mat3& R) { return logSO3(R).norm(); }

}  // namespace livo
