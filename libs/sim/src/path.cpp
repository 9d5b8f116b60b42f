// Geometric paths and their timing: the construction half of SimTrajectory (see trajectory.hpp).
#include "livo/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace livo::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Carrying height and path extents chosen from the world when the scenario leaves them at 0; sway and
// bob from the motion when the scenario leaves them out.
TrajectoryConfig withDefaults(TrajectoryConfig c, const WorldConfig& w) {
  c.sway_deg = c.swayDegIn(w);
  c.bob_m = c.bobMIn(w);
  c.motion = c.motionIn(w);
  if (c.height_m <= 0.0) c.height_m = w.kind == "street" ? 1.8 : 1.4;
  if (c.center_m.z() == 0.0) c.center_m.z() = c.height_m;
  Vec3 def;
  if (w.kind == "room") def = Vec3(0.55 * w.size_m.x(), 0.55 * w.size_m.y(), 0.3);
  else if (w.kind == "corridor") def = Vec3(std::min(64.0, 0.5 * w.size_m.x()), 0.35 * w.size_m.y(), 0.1);
  else if (w.kind == "street") def = Vec3(w.size_m.x(), w.size_m.y(), 0.0);
  else def = Vec3(1.0, 4.0, 1.0);  // wall
  for (int i = 0; i < 3; ++i)
    if (c.size_m[i] <= 0.0) c.size_m[i] = def[i];
  return c;
}

// Rounded rectangle X by Y with corner radius r, counter-clockwise from the middle of the -y side.
std::vector<Vec3> roundedRectangle(const TrajectoryConfig& c, double radius) {
  const double X = c.size_m.x(), Y = c.size_m.y();
  const double r = std::min(radius, 0.5 * std::min(X, Y));
  const double hx = 0.5 * X - r, hy = 0.5 * Y - r;  // half straight lengths
  const double step = std::max(0.002, std::min(0.5, r * 0.02));
  std::vector<Vec3> pts;
  auto straight = [&](double x0, double y0, double x1, double y1) {
    const double len = std::hypot(x1 - x0, y1 - y0);
    const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
    for (int i = 0; i < n; ++i) pts.emplace_back(x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n, 0.0);
  };
  auto arc = [&](double cx, double cy, double a0) {
    const int n = std::max(4, static_cast<int>(std::ceil(0.5 * kPi * r / step)));
    for (int i = 0; i < n; ++i) {
      const double a = a0 + 0.5 * kPi * i / n;
      pts.emplace_back(cx + r * std::cos(a), cy + r * std::sin(a), 0.0);
    }
  };
  straight(0.0, -0.5 * Y, hx, -0.5 * Y);
  arc(hx, -hy, -0.5 * kPi);
  straight(0.5 * X, -hy, 0.5 * X, hy);
  arc(hx, hy, 0.0);
  straight(hx, 0.5 * Y, -hx, 0.5 * Y);
  arc(-hx, hy, 0.5 * kPi);
  straight(-0.5 * X, hy, -0.5 * X, -hy);
  arc(-hx, -hy, kPi);
  straight(-hx, -0.5 * Y, 0.0, -0.5 * Y);
  // Vertical wave: two periods per lap, peak to peak size_m.z.
  double total = 0.0;
  std::vector<double> s(pts.size(), 0.0);
  for (std::size_t i = 1; i < pts.size(); ++i) s[i] = total += (pts[i] - pts[i - 1]).norm();
  total += (pts.front() - pts.back()).norm();
  for (std::size_t i = 0; i < pts.size(); ++i) {
    pts[i] += c.center_m;
    pts[i].z() += 0.5 * c.size_m.z() * std::sin(4.0 * kPi * s[i] / total);
  }
  return pts;
}

std::vector<Vec3> lissajous(const TrajectoryConfig& c) {
  const int n = 20000;
  std::vector<Vec3> pts;
  pts.reserve(n);
  for (int i = 0; i < n; ++i) {
    const double phi = 2.0 * kPi * i / n;
    pts.push_back(c.center_m + 0.5 * Vec3(c.size_m.x() * std::sin(c.frequencies.x() * phi + 0.5),
                                           c.size_m.y() * std::sin(c.frequencies.y() * phi),
                                           c.size_m.z() * std::sin(c.frequencies.z() * phi + 1.0)));
  }
  return pts;
}

// Closed centripetal Catmull-Rom spline through the waypoints (Yuksel et al. 2011): no cusps or
// self-intersections inside a segment.
std::vector<Vec3> waypointPath(const TrajectoryConfig& c) {
  std::vector<Vec3> w;
  for (std::size_t i = 0; i + 2 < c.waypoints.size(); i += 3)
    w.emplace_back(c.waypoints[i], c.waypoints[i + 1], c.waypoints[i + 2]);
  const std::size_t n = w.size();
  std::vector<Vec3> pts;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 &p0 = w[(i + n - 1) % n], &p1 = w[i], &p2 = w[(i + 1) % n], &p3 = w[(i + 2) % n];
    const double t0 = 0.0;
    const double t1 = t0 + std::sqrt(std::max((p1 - p0).norm(), 1e-6));
    const double t2 = t1 + std::sqrt(std::max((p2 - p1).norm(), 1e-6));
    const double t3 = t2 + std::sqrt(std::max((p3 - p2).norm(), 1e-6));
    const int m = 400;
    for (int k = 0; k < m; ++k) {
      const double t = t1 + (t2 - t1) * k / m;
      const Vec3 a1 = (t1 - t) / (t1 - t0) * p0 + (t - t0) / (t1 - t0) * p1;
      const Vec3 a2 = (t2 - t) / (t2 - t1) * p1 + (t - t1) / (t2 - t1) * p2;
      const Vec3 a3 = (t3 - t) / (t3 - t2) * p2 + (t - t2) / (t3 - t2) * p3;
      const Vec3 b1 = (t2 - t) / (t2 - t0) * a1 + (t - t0) / (t2 - t0) * a2;
      const Vec3 b2 = (t3 - t) / (t3 - t1) * a2 + (t - t1) / (t3 - t1) * a3;
      pts.push_back((t2 - t) / (t2 - t1) * b1 + (t - t1) / (t2 - t1) * b2);
    }
  }
  return pts;
}

// Resamples a closed polyline at (almost) uniform arc length `ds`.
std::vector<Vec3> resample(const std::vector<Vec3>& in, double& ds, double& length) {
  std::vector<double> s(in.size() + 1, 0.0);
  for (std::size_t i = 0; i < in.size(); ++i) s[i + 1] = s[i] + (in[(i + 1) % in.size()] - in[i]).norm();
  length = s.back();
  const int n = std::max(64, static_cast<int>(std::round(length / ds)));
  ds = length / n;
  std::vector<Vec3> out;
  out.reserve(static_cast<std::size_t>(n));
  std::size_t j = 0;
  for (int i = 0; i < n; ++i) {
    const double si = ds * i;
    while (j + 1 < s.size() - 1 && s[j + 1] < si) ++j;
    const double seg = s[j + 1] - s[j];
    const double f = seg > 0.0 ? (si - s[j]) / seg : 0.0;
    out.push_back(in[j] + f * (in[(j + 1) % in.size()] - in[j]));
  }
  return out;
}

}  // namespace

std::vector<Vec3> makePathPolyline(const TrajectoryConfig& cfg_in, const WorldConfig& world) {
  const TrajectoryConfig c = withDefaults(cfg_in, world);
  std::vector<Vec3> raw;
  if (c.kind == "lissajous") raw = lissajous(c);
  else if (c.kind == "waypoints") raw = waypointPath(c);
  else {
    double r = c.corner_radius_m;
    if (r <= 0.0) r = world.kind == "street" ? 25.0 : 0.5 * std::min(c.size_m.x(), c.size_m.y());
    raw = roundedRectangle(c, r);
  }
  double length = 0.0;
  double ds = 0.02;
  for (std::size_t i = 0; i < raw.size(); ++i) length += (raw[(i + 1) % raw.size()] - raw[i]).norm();
  ds = std::clamp(length / 40000.0, 0.01, 0.5);
  std::vector<Vec3> path = resample(raw, ds, length);
  // Start `start_m` metres along the loop (negative: before its nominal start).
  const double shift = std::fmod(std::fmod(c.start_m, length) + length, length);
  const auto k = static_cast<std::size_t>(std::lround(shift / ds)) % path.size();
  std::rotate(path.begin(), path.begin() + static_cast<std::ptrdiff_t>(k), path.end());
  return path;
}

// Sway angular-rate bound (rad/s) of the sway functions in trajectory.cpp, per radian of amplitude:
// sum of |amplitude * 2 pi f| per axis, combined as a vector norm.
double swayRateBound(double amplitude_rad);

namespace {

// Turn rate per metre of the horizontal heading at each sample of a closed path: the heading change
// between the chords to and from +-m samples (~0.2 m baseline, robust to the polyline's vertices),
// divided by the arc length between the chords' midpoints. Facing `target` (when given), the heading
// also turns by v_perp / distance.
std::vector<double> headingCurvature(const std::vector<Vec3>& path, double path_length, const Vec3* target) {
  const std::size_t n = path.size();
  const std::size_t m = std::max<std::size_t>(1, static_cast<std::size_t>(0.2 / (path_length / n)));
  std::vector<double> kappa(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 a = path[i] - path[(i + n - m) % n], b = path[(i + m) % n] - path[i];
    const double turn = std::atan2(a.x() * b.y() - a.y() * b.x(), a.x() * b.x() + a.y() * b.y());
    kappa[i] = std::abs(turn) / std::max(0.5 * (a.norm() + b.norm()), 1e-9);
    if (target) {
      const double d = std::hypot(target->x() - path[i].x(), target->y() - path[i].y());
      kappa[i] = std::max(kappa[i], 1.0 / std::max(d, 0.3));
    }
  }
  return kappa;
}

// Maximum over a window of +-win samples around each sample (cyclic).
std::vector<double> cyclicWindowMax(const std::vector<double>& x, int win) {
  const std::size_t n = x.size();
  std::vector<double> out(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    double m = 0.0;
    for (int k = -win; k <= win; ++k) {
      const auto idx = (static_cast<long long>(i) + k + static_cast<long long>(n)) % static_cast<long long>(n);
      m = std::max(m, x[static_cast<std::size_t>(idx)]);
    }
    out[i] = m;
  }
  return out;
}

// Speed at each sample: cruise limit, turn-rate (`turn_budget` rad/s) and lateral-acceleration limits,
// then forward / backward passes that bound the tangential acceleration (v^2 = v0^2 + 2 a ds), twice
// around the loop. seg[i]: length from sample i to i + 1.
std::vector<double> speedProfile(const std::vector<double>& curvature, const std::vector<double>& seg,
                                 const TrajectoryConfig& c, double turn_budget) {
  const std::size_t n = curvature.size();
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double k = std::max(curvature[i], 1e-9);
    v[i] = std::min({c.speed_mps, turn_budget / k, std::sqrt(c.max_accel_mps2 / k)});
  }
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i < 2 * n; ++i) {
      const std::size_t a = i % n, b = (i + 1) % n;
      v[b] = std::min(v[b], std::sqrt(v[a] * v[a] + 2.0 * c.max_accel_mps2 * seg[a]));
    }
    for (std::size_t i = 2 * n; i > 0; --i) {
      const std::size_t b = i % n, a = (i - 1) % n;
      v[a] = std::min(v[a], std::sqrt(v[b] * v[b] + 2.0 * c.max_accel_mps2 * seg[a]));
    }
  }
  return v;
}

}  // namespace

SimTrajectory::SimTrajectory(const TrajectoryConfig& cfg_in, const WorldConfig& world)
    : cfg_(withDefaults(cfg_in, world)) {
  path_ = makePathPolyline(cfg_in, world);
  const std::size_t n = path_.size();
  std::vector<double> seg(n);  // length from sample i to i + 1
  path_length_ = 0.0;
  for (std::size_t i = 0; i < n; ++i) path_length_ += seg[i] = (path_[(i + 1) % n] - path_[i]).norm();
  if (path_length_ < 0.5) throw ConfigError("trajectory: the path is shorter than 0.5 m");
  look_at_ = cfg_.look_at.size() == 3;
  if (look_at_) target_ = Vec3(cfg_.look_at[0], cfg_.look_at[1], cfg_.look_at[2]);

  // 1. Turn rate per metre (curvature of the horizontal heading), smoothed over ~0.3 m.
  const double max_rot = cfg_.max_rot_dps * kPi / 180.0;
  const double budget = 0.85 * max_rot - swayRateBound(*cfg_.sway_deg * kPi / 180.0);
  if (budget < 0.2 * max_rot)
    throw ConfigError("trajectory.max_rot_dps: " + std::to_string(cfg_.max_rot_dps) +
                      " leaves too little turn rate beside the sway (lower trajectory.sway_deg)");
  const std::vector<double> kappa = headingCurvature(path_, path_length_, look_at_ ? &target_ : nullptr);
  const int win = std::max(1, static_cast<int>(0.3 / (path_length_ / n)));
  const std::vector<double> smooth = cyclicWindowMax(kappa, win);

  // 2. Speed profile within the limits.
  const std::vector<double> v = speedProfile(smooth, seg, cfg_, budget);

  // 3. Control points at uniform time steps.
  placeControlPoints(seg, v);

  // 4. Check the limits on the final spline (with sway) and slow the whole lap down if needed.
  fitTimeScale(max_rot);
}

void SimTrajectory::placeControlPoints(const std::vector<double>& seg, const std::vector<double>& v) {
  // Time of each sample, then control points at uniform time steps (knots every ~0.2 s).
  const std::size_t n = path_.size();
  std::vector<double> t(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) t[i + 1] = t[i] + seg[i] / (0.5 * (v[i] + v[(i + 1) % n]));
  const double lap = t[n];
  const int knots = std::max(16, static_cast<int>(std::round(lap / 0.2)));
  knot_dt_ = lap / knots;
  ctrl_.clear();
  std::size_t j = 0;
  for (int k = 0; k < knots; ++k) {
    const double tk = knot_dt_ * k;
    while (j + 1 < n && t[j + 1] < tk) ++j;
    const double f = (tk - t[j]) / (t[j + 1] - t[j]);
    ctrl_.push_back(path_[j] + f * (path_[(j + 1) % n] - path_[j]));
  }
}

void SimTrajectory::fitTimeScale(double max_rot) {
  time_scale_ = 1.0;
  for (int iter = 0; iter < 8; ++iter) {
    measurePeaks();
    const double f = std::min({1.0, cfg_.speed_mps / peak_speed_, max_rot / peak_rate_});
    if (f >= 0.999) break;
    time_scale_ *= 0.98 * f;
  }
  if (peak_rate_ > max_rot * 1.001 || peak_speed_ > cfg_.speed_mps * 1.001)
    throw ConfigError("trajectory: cannot respect speed_mps / max_rot_dps on this path");
}

}  // namespace livo::sim
