// Equidistant (Kannala-Brandt) fisheye, OpenCV cv::fisheye's model; equations in camera_model.hpp.
#include "livo/sensors/camera_model.hpp"

#include <cmath>
#include <cstdio>

namespace livo {

namespace {
constexpr double kAngleCap = 179.0 * M_PI / 180.0;  // rays closer than 1 deg to -z are never valid
constexpr double kScanStep = 1e-3;                   // rad, scan for the first fold of eq. (3)
constexpr double kUnprojectTol = 1e-13;              // residual of eq. (3), rad
constexpr double kSmallRadius = 1e-9;                // r / Z below which the pinhole limit is used
constexpr int kMaxIterations = 100;
}  // namespace

Equidistant::Equidistant(int width, int height, double fx, double fy, double cx, double cy,
                         const std::array<double, 4>& d)
    : CameraModel(width, height, fx, fy, cx, cy, d) {
  // The valid range ends where theta_d(theta) stops increasing (or at the cap): scan, then bisect.
  theta_max_ = kAngleCap;
  double prev = 0.0;
  for (double th = kScanStep; th <= kAngleCap; th += kScanStep) {
    double deriv = 0;
    distortAngle(th, &deriv);
    if (!(deriv > 0)) {
      double lo = prev, hi = th;
      for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        distortAngle(mid, &deriv);
        (deriv > 0 ? lo : hi) = mid;
      }
      theta_max_ = lo;
      break;
    }
    prev = th;
  }
  theta_d_max_ = distortAngle(theta_max_);
}

double Equidistant::distortAngle(double theta, double* deriv) const {
  const double t2 = theta * theta;
  const double k1 = d_[0], k2 = d_[1], k3 = d_[2], k4 = d_[3];
  const double poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)));  // eq. (3)
  if (deriv) *deriv = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)));
  return theta * poly;
}

bool Equidistant::project(const Eigen::Vector3d& p_cam, Eigen::Vector2d& px, Eigen::Matrix<double, 2, 3>* J) const {
  const double X = p_cam.x(), Y = p_cam.y(), Z = p_cam.z();
  const double r2 = X * X + Y * Y, r = std::sqrt(r2);
  if (Z > 0 && r <= kSmallRadius * Z) {
    // Near the optical axis theta_d / r -> 1 / Z (error O(theta^2) < 1e-17): the pinhole limit.
    const double iz = 1.0 / Z;
    px.x() = fx_ * X * iz + cx_;
    px.y() = fy_ * Y * iz + cy_;
    if (J) *J = projectionJacobianPinhole(p_cam, fx_, fy_);
    return true;
  }
  const double theta = std::atan2(r, Z);
  if (!(theta <= theta_max_) || !(r > 0)) return false;  // also rejects NaN and the zero vector
  double dtd = 0;
  const double td = distortAngle(theta, J ? &dtd : nullptr);
  const double s = td / r;  // x_d = s X, y_d = s Y
  px.x() = fx_ * s * X + cx_;
  px.y() = fy_ * s * Y + cy_;
  if (J) {
    // theta = atan2(r, Z): d theta / d(X, Y) = Z (X, Y) / (r rho^2), d theta / d Z = -r / rho^2.
    // s = td / r: d s / d(X, Y) = a (X, Y) with a = td' Z / (r^2 rho^2) - td / r^3,
    //             d s / d Z = -td' / rho^2.
    const double rho2 = r2 + Z * Z;
    const double a = dtd * Z / (r2 * rho2) - td / (r2 * r);
    const double sz = -dtd / rho2;
    Eigen::Matrix<double, 2, 3> Jd;  // d (x_d, y_d) / d p
    Jd << s + a * X * X, a * X * Y, sz * X,  //
        a * X * Y, s + a * Y * Y, sz * Y;
    Jd.row(0) *= fx_;
    Jd.row(1) *= fy_;
    *J = Jd;
  }
  return true;
}

bool Equidistant::unproject(const Eigen::Vector2d& px, Eigen::Vector3d& bearing) const {
  const double xd = (px.x() - cx_) / fx_, yd = (px.y() - cy_) / fy_;
  const double td = std::hypot(xd, yd);
  if (!(td <= theta_d_max_)) return false;  // beyond the valid angle, or NaN
  if (td < 1e-15) {
    bearing = Eigen::Vector3d(xd, yd, 1.0).normalized();
    return true;
  }
  // Solve theta_d(theta) = td on [0, theta_max] (monotonic there): Newton kept inside a shrinking
  // bracket, bisection when a Newton step leaves it.
  double lo = 0.0, hi = theta_max_, theta = std::min(td, theta_max_);
  bool converged = false;
  for (int it = 0; it < kMaxIterations; ++it) {
    double deriv = 0;
    const double f = distortAngle(theta, &deriv) - td;
    if (std::abs(f) < kUnprojectTol) {
      converged = true;
      break;
    }
    (f > 0 ? hi : lo) = theta;
    if (hi - lo <= 4e-16 * hi) {
      converged = true;  // bracket at machine precision (only near a fold, where the slope vanishes)
      break;
    }
    double next = theta - f / deriv;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    theta = next;
  }
  if (!converged) return false;
  const double st = std::sin(theta) / td;
  bearing = Eigen::Vector3d(st * xd, st * yd, std::cos(theta));
  return true;
}

std::string Equidistant::describe() const {
  char buf[320];
  std::snprintf(buf, sizeof(buf),
                "equidistant %dx%d fx=%.6g fy=%.6g cx=%.6g cy=%.6g k1=%.6g k2=%.6g k3=%.6g k4=%.6g "
                "max_angle=%.2f deg",
                width_, height_, fx_, fy_, cx_, cy_, d_[0], d_[1], d_[2], d_[3], theta_max_ * 180.0 / M_PI);
  return buf;
}

}  // namespace livo
