#include "livo/viewer/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace livo::viewer {

std::array<Vec3, 5> frustumCorners(const FrustumIntrinsics& k, const Pose& T_world_cam, double depth_m) {
  // Back-projection of a pixel (u, v) at depth d: d * ((u - cx) / fx, (v - cy) / fy, 1) in the camera.
  const auto corner = [&](double u, double v) {
    return T_world_cam * Vec3(depth_m * (u - k.cx) / k.fx, depth_m * (v - k.cy) / k.fy, depth_m);
  };
  const double w = k.width, h = k.height;
  return {T_world_cam.translation(), corner(0, 0), corner(w, 0), corner(w, h), corner(0, h)};
}

const std::vector<std::pair<int, int>>& frustumSegments() {
  static const std::vector<std::pair<int, int>> kSegments{{0, 1}, {0, 2}, {0, 3}, {0, 4},
                                                           {1, 2}, {2, 3}, {3, 4}, {4, 1}};
  return kSegments;
}

std::string viewModeName(ViewMode m) {
  switch (m) {
    case ViewMode::kFollow: return "follow";
    case ViewMode::kTop: return "top";
    case ViewMode::kFree: return "free";
  }
  return "follow";
}

bool parseViewMode(const std::string& name, ViewMode& out) {
  for (const ViewMode m : {ViewMode::kFollow, ViewMode::kTop, ViewMode::kFree})
    if (viewModeName(m) == name) {
      out = m;
      return true;
    }
  return false;
}

ViewMode nextViewMode(ViewMode m) {
  switch (m) {
    case ViewMode::kFollow: return ViewMode::kTop;
    case ViewMode::kTop: return ViewMode::kFree;
    case ViewMode::kFree: return ViewMode::kFollow;
  }
  return ViewMode::kFollow;
}

ViewCamera FollowCamera::update(const Pose& T_world_imu, double t_s) {
  const Vec3 x_world = T_world_imu.linear().col(0);
  const double target = std::atan2(x_world.y(), x_world.x());
  if (!started_ || !(t_s > last_t_)) {
    if (!started_) heading_ = target;
    started_ = true;
  } else {
    // First-order low pass on the angle: heading += (1 - exp(-dt / tau)) * wrap(target - heading).
    const double a = 1.0 - std::exp(-(t_s - last_t_) / std::max(1e-6, cfg_.heading_tau_s));
    heading_ += a * std::remainder(target - heading_, 2.0 * M_PI);
    heading_ = std::remainder(heading_, 2.0 * M_PI);
  }
  last_t_ = std::max(last_t_, t_s);
  const Vec3 forward(std::cos(heading_), std::sin(heading_), 0.0);
  const Vec3 p = T_world_imu.translation();
  ViewCamera c;
  c.focal = p + cfg_.look_ahead_m * forward;
  c.position = p - cfg_.distance_m * forward + Vec3(0, 0, cfg_.height_m);
  c.up = Vec3::UnitZ();
  c.parallel = false;
  return c;
}

void robustBounds(const std::vector<Eigen::Vector3f>& points, double q, Vec3& lo, Vec3& hi) {
  lo = hi = Vec3::Zero();
  if (points.empty()) return;
  const std::size_t step = std::max<std::size_t>(1, points.size() / 20'000);  // enough samples for a box
  std::vector<float> v;
  v.reserve(points.size() / step + 1);
  for (int a = 0; a < 3; ++a) {
    v.clear();
    for (std::size_t i = 0; i < points.size(); i += step) v.push_back(points[i][a]);
    const auto at = [&](double f) {
      const auto k = static_cast<std::ptrdiff_t>(std::clamp(f, 0.0, 1.0) * double(v.size() - 1) + 0.5);
      std::nth_element(v.begin(), v.begin() + k, v.end());
      return double(v[static_cast<std::size_t>(k)]);
    };
    lo[a] = at(q);
    hi[a] = at(1.0 - q);
  }
}

ViewCamera topCamera(const Vec3& lo, const Vec3& hi, double aspect, double margin, double top_reserve) {
  const Vec3 centre = 0.5 * (lo + hi);
  const Vec3 size = (hi - lo).cwiseMax(Vec3::Constant(1.0));  // at least 1 m
  const double pad = 1.0 + 2.0 * margin;
  const double a = aspect > 0.0 ? aspect : 1.0;
  const double r = std::clamp(top_reserve, 0.0, 0.5);
  ViewCamera c;
  c.parallel = true;
  // parallel_scale s is half the visible height (the width is aspect times that). The box goes into the
  // lower 1 - r of the height: centred there when the focal point sits r s above its centre.
  c.parallel_scale = 0.5 * pad * std::max(size.y() / (1.0 - r), size.x() / a);
  c.focal = centre + Vec3(0, r * c.parallel_scale, 0);
  c.position = c.focal + Vec3(0, 0, size.z() + 10.0 + c.parallel_scale);
  c.up = Vec3::UnitY();
  return c;
}

}  // namespace livo::viewer
