#include "livo/sim/camera_model.hpp"

#include <algorithm>
#include <cmath>

namespace livo::sim {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

SimCameraModel::SimCameraModel(const CameraSimConfig& cfg) : cfg_(cfg), fisheye_(cfg.model == "equidistant") {
  const int w = cfg_.width, h = cfg_.height;
  rays_.assign(static_cast<std::size_t>(w) * h, Eigen::Vector3f::UnitZ());
  valid_.assign(rays_.size(), 0);
  pixel_angle_.assign(rays_.size(), 0.f);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * w + c;
      Vec3 ray, ray_u, ray_v;
      if (!unproject({c, r}, ray) || !unproject({c + 0.5, r}, ray_u) || !unproject({c, r + 0.5}, ray_v)) continue;
      if (fisheye_ && std::acos(std::clamp(ray.z(), -1.0, 1.0)) > cfg_.max_angle_deg * kPi / 180.0) continue;
      rays_[i] = ray.cast<float>();
      valid_[i] = 1;
      // Pixel footprint: geometric mean of the angles spanned by one pixel along u and v.
      const double au = 2.0 * std::acos(std::clamp(ray.dot(ray_u), -1.0, 1.0));
      const double av = 2.0 * std::acos(std::clamp(ray.dot(ray_v), -1.0, 1.0));
      pixel_angle_[i] = static_cast<float>(std::sqrt(au * av));
    }
}

void SimCameraModel::distort(double x, double y, double& xd, double& yd) const {
  const auto& k = cfg_.distortion;
  const double r2 = x * x + y * y;
  const double radial = 1.0 + k[0] * r2 + k[1] * r2 * r2;
  xd = x * radial + 2.0 * k[2] * x * y + k[3] * (r2 + 2.0 * x * x);
  yd = y * radial + k[2] * (r2 + 2.0 * y * y) + 2.0 * k[3] * x * y;
}

bool SimCameraModel::project(const Vec3& p, Eigen::Vector2d& uv) const {
  if (fisheye_) {
    // theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8), radius fx * theta_d.
    const double r = std::hypot(p.x(), p.y());
    const double theta = std::atan2(r, p.z());
    if (theta > cfg_.max_angle_deg * kPi / 180.0) return false;
    const auto& k = cfg_.distortion;
    const double t2 = theta * theta;
    const double td = theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
    const double sx = r > 1e-12 ? p.x() / r : 0.0, sy = r > 1e-12 ? p.y() / r : 0.0;
    uv = {cfg_.fx * td * sx + cfg_.cx, cfg_.fy * td * sy + cfg_.cy};
    return true;
  }
  if (p.z() <= 1e-9) return false;
  double xd, yd;
  distort(p.x() / p.z(), p.y() / p.z(), xd, yd);
  uv = {cfg_.fx * xd + cfg_.cx, cfg_.fy * yd + cfg_.cy};
  return true;
}

bool SimCameraModel::unproject(const Eigen::Vector2d& uv, Vec3& ray) const {
  const double xd = (uv.x() - cfg_.cx) / cfg_.fx, yd = (uv.y() - cfg_.cy) / cfg_.fy;
  if (fisheye_) {
    const double td = std::hypot(xd, yd);
    const auto& k = cfg_.distortion;
    double theta = td;  // Newton on f(theta) = theta_d(theta) - td
    for (int it = 0; it < 30; ++it) {
      const double t2 = theta * theta;
      const double f = theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) - td;
      const double df = 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
      if (std::abs(df) < 1e-9) return false;
      theta -= f / df;
    }
    if (!(theta >= 0.0 && theta < kPi)) return false;
    const double sx = td > 1e-12 ? xd / td : 0.0, sy = td > 1e-12 ? yd / td : 0.0;
    ray = Vec3(std::sin(theta) * sx, std::sin(theta) * sy, std::cos(theta));
    Eigen::Vector2d check;
    return project(ray, check) && (check - uv).norm() < 1e-6;
  }
  // Pinhole: Gauss-Newton on distort(x, y) = (xd, yd) with a numeric Jacobian.
  double x = xd, y = yd;
  for (int it = 0; it < 30; ++it) {
    double fx, fy;
    distort(x, y, fx, fy);
    const double ex = fx - xd, ey = fy - yd;
    if (ex * ex + ey * ey < 1e-26) break;
    const double e = 1e-7;
    double ax, ay, bx, by;
    distort(x + e, y, ax, ay);
    distort(x, y + e, bx, by);
    const double j00 = (ax - fx) / e, j10 = (ay - fy) / e, j01 = (bx - fx) / e, j11 = (by - fy) / e;
    const double det = j00 * j11 - j01 * j10;
    if (std::abs(det) < 1e-12) return false;
    x -= (j11 * ex - j01 * ey) / det;
    y -= (-j10 * ex + j00 * ey) / det;
  }
  ray = Vec3(x, y, 1.0).normalized();
  Eigen::Vector2d check;
  return project(ray, check) && (check - uv).norm() < 1e-6;
}

}  // namespace livo::sim
