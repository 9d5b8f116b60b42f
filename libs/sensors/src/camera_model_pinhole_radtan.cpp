// Pinhole + radial-tangential distortion (OpenCV's model with [k1, k2, p1, p2]); equations in
// camera_model.hpp.
#include "livo/sensors/camera_model.hpp"

#include <cmath>
#include <cstdio>

namespace livo {

namespace {
constexpr double kRadiusCap = 1e6;         // normalised radius beyond which nothing can be imaged
constexpr double kUnprojectTol = 1e-12;    // residual of eq. (1), normalised units
constexpr int kMaxNewtonIterations = 50;
constexpr int kMaxHalvings = 40;
}  // namespace

PinholeRadtan::PinholeRadtan(int width, int height, double fx, double fy, double cx, double cy,
                             const std::array<double, 4>& d)
    : CameraModel(width, height, fx, fy, cx, cy, d) {
  // The radial map r -> r (1 + k1 r^2 + k2 r^4) increases while 1 + 3 k1 t + 5 k2 t^2 > 0, t = r^2:
  // the valid region ends at its smallest positive root (tangential terms are ignored for this limit).
  const double k1 = d[0], k2 = d[1];
  double t_max = kRadiusCap * kRadiusCap;
  if (k2 == 0.0) {
    if (k1 < 0) t_max = std::min(t_max, -1.0 / (3.0 * k1));
  } else {
    const double disc = 9.0 * k1 * k1 - 20.0 * k2;
    if (disc >= 0) {
      const double sq = std::sqrt(disc);
      for (double t : {(-3.0 * k1 - sq) / (10.0 * k2), (-3.0 * k1 + sq) / (10.0 * k2)})
        if (t > 0) t_max = std::min(t_max, t);
    }
  }
  r2_max_ = t_max;
  r_max_ = std::sqrt(t_max);
}

Eigen::Vector2d PinholeRadtan::distort(const Eigen::Vector2d& xy, Eigen::Matrix2d* Jd) const {
  const double k1 = d_[0], k2 = d_[1], p1 = d_[2], p2 = d_[3];
  const double x = xy.x(), y = xy.y();
  const double x2 = x * x, y2 = y * y, xy2 = 2.0 * x * y, r2 = x2 + y2;
  const double g = 1.0 + r2 * (k1 + k2 * r2);  // eq. (1)
  const Eigen::Vector2d out(x * g + p1 * xy2 + p2 * (r2 + 2.0 * x2), y * g + p1 * (r2 + 2.0 * y2) + p2 * xy2);
  if (Jd) {
    const double dg = 2.0 * (k1 + 2.0 * k2 * r2);  // d g / d x = dg x, d g / d y = dg y
    (*Jd)(0, 0) = g + dg * x2 + 2.0 * p1 * y + 6.0 * p2 * x;
    (*Jd)(0, 1) = dg * x * y + 2.0 * p1 * x + 2.0 * p2 * y;
    (*Jd)(1, 0) = (*Jd)(0, 1);
    (*Jd)(1, 1) = g + dg * y2 + 6.0 * p1 * y + 2.0 * p2 * x;
  }
  return out;
}

bool PinholeRadtan::project(const Eigen::Vector3d& p_cam, Eigen::Vector2d& px, Eigen::Matrix<double, 2, 3>* J) const {
  const double z = p_cam.z();
  if (!(z > 0)) return false;
  const double iz = 1.0 / z;
  const Eigen::Vector2d xy(p_cam.x() * iz, p_cam.y() * iz);
  if (!(xy.squaredNorm() <= r2_max_)) return false;  // also rejects NaN / inf
  Eigen::Matrix2d Jd;
  const Eigen::Vector2d xyd = distort(xy, J ? &Jd : nullptr);
  px.x() = fx_ * xyd.x() + cx_;  // eq. (2)
  px.y() = fy_ * xyd.y() + cy_;
  if (J) {
    // d px / d p = diag(fx, fy) * d x_d / d x * d x / d p,  d x / d p = [1/z 0 -x/z; 0 1/z -y/z].
    Eigen::Matrix<double, 2, 3> Jn;
    Jn << iz, 0.0, -xy.x() * iz, 0.0, iz, -xy.y() * iz;
    *J = Jd * Jn;
    J->row(0) *= fx_;
    J->row(1) *= fy_;
  }
  return true;
}

bool PinholeRadtan::unproject(const Eigen::Vector2d& px, Eigen::Vector3d& bearing) const {
  const Eigen::Vector2d target((px.x() - cx_) / fx_, (px.y() - cy_) / fy_);
  if (!target.allFinite()) return false;
  // Newton on distort(x) = target from x = target, with step halving so the residual always decreases
  // and x stays in the valid region.
  Eigen::Vector2d x = target;
  Eigen::Matrix2d Jd;
  Eigen::Vector2d f = distort(x, &Jd) - target;
  double fn = f.norm();
  bool converged = fn < kUnprojectTol;
  for (int it = 0; it < kMaxNewtonIterations && !converged; ++it) {
    const double det = Jd.determinant();
    if (!(std::abs(det) > 1e-300)) return false;
    Eigen::Matrix2d Jinv;
    Jinv << Jd(1, 1), -Jd(0, 1), -Jd(1, 0), Jd(0, 0);
    const Eigen::Vector2d dx = -(Jinv * f) / det;
    double step = 1.0;
    bool accepted = false;
    for (int h = 0; h < kMaxHalvings; ++h, step *= 0.5) {
      const Eigen::Vector2d xn = x + step * dx;
      if (!(xn.squaredNorm() <= r2_max_)) continue;
      Eigen::Matrix2d Jn;
      const Eigen::Vector2d fnew = distort(xn, &Jn) - target;
      const double nn = fnew.norm();
      if (nn < fn || nn < kUnprojectTol) {
        x = xn, f = fnew, fn = nn, Jd = Jn;
        accepted = true;
        break;
      }
    }
    if (!accepted) return false;
    converged = fn < kUnprojectTol;
  }
  if (!converged) return false;
  bearing = Eigen::Vector3d(x.x(), x.y(), 1.0).normalized();
  return true;
}

std::string PinholeRadtan::describe() const {
  char buf[320];
  std::snprintf(buf, sizeof(buf),
                "pinhole-radtan %dx%d fx=%.6g fy=%.6g cx=%.6g cy=%.6g k1=%.6g k2=%.6g p1=%.6g p2=%.6g "
                "max_radius=%.6g (%.2f deg)",
                width_, height_, fx_, fy_, cx_, cy_, d_[0], d_[1], d_[2], d_[3], r_max_,
                std::atan(r_max_) * 180.0 / M_PI);
  return buf;
}

}  // namespace livo
