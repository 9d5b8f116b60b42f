// Random rigs: the distribution of config/sim/README.md, section "Random rigs".
#include "livo/sim/random_scenario.hpp"

#include "livo/common/so3.hpp"
#include "livo/sim/random.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace livo::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  std::string s = buf;
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

/// Shortest form for the summary line ("10", "0.26").
std::string g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::string vec(std::initializer_list<double> v) {
  std::string s = "[";
  bool first = true;
  for (double x : v) {
    s += (first ? "" : ", ") + num(x);
    first = false;
  }
  return s + "]";
}

class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(hashKeys(seed, 0x52414E44524947ull /* "RANDRIG" */)) {}
  double uniform(double lo, double hi) { return rng_.uniform(lo, hi); }
  double logUniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  bool chance(double p) { return rng_.uniform() < p; }
  double gaussian() { return rng_.gaussian(); }
  /// Index drawn with the given weights.
  std::size_t pick(std::initializer_list<double> weights) {
    double total = 0;
    for (double w : weights) total += w;
    double u = rng_.uniform() * total;
    std::size_t i = 0;
    for (double w : weights) {
      if (u < w) return i;
      u -= w;
      ++i;
    }
    return weights.size() - 1;
  }

 private:
  SplitMix rng_;
};

/// [x, y, z, qx, qy, qz, qw] of a pose.
std::string poseText(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  return vec({t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()});
}

Eigen::Quaterniond smallTilt(Draw& d, double max_deg) {
  const Eigen::Vector3d w(d.uniform(-max_deg, max_deg), d.uniform(-max_deg, max_deg), d.uniform(-max_deg, max_deg));
  return Eigen::Quaterniond(Eigen::AngleAxisd(w.norm() * kDeg, w.norm() > 0 ? w.normalized() : Eigen::Vector3d::UnitX()));
}

}  // namespace

RandomScenario drawRandomScenario(std::uint64_t seed, double duration_s) {
  Draw d(seed);
  std::ostringstream y, sum;
  y << "# Random rig " << seed << " (livo-sim --random " << seed
    << "): drawn from the distribution of config/sim/README.md, section \"Random rigs\".\n"
    << "seed: " << (seed % 1000000007ull) << "\n"
    << "duration_s: " << num(duration_s) << "\n\n";

  // --- World.
  static const char* kWorlds[] = {"room", "corridor", "street", "wall"};
  const std::string world = kWorlds[d.pick({0.35, 0.25, 0.25, 0.15})];
  Eigen::Vector3d size;
  double clutter = 0.0, tex_scale = d.logUniform(0.5, 2.0);
  if (world == "room") {
    size = {d.uniform(5.0, 14.0), d.uniform(4.0, 10.0), d.uniform(2.5, 4.0)};
    clutter = d.uniform(0.2, 0.9);
  } else if (world == "corridor") {
    size = {200.0, d.uniform(1.8, 4.0), d.uniform(2.4, 3.5)};
  } else if (world == "street") {
    size = {d.uniform(200.0, 700.0), d.uniform(150.0, 400.0), d.uniform(12.0, 35.0)};
    clutter = d.uniform(0.2, 0.8);
    tex_scale = d.logUniform(1.0, 3.0);
  } else {
    size = {d.uniform(2.5, 6.0), d.uniform(20.0, 40.0), d.uniform(10.0, 20.0)};
  }
  y << "world:\n  kind: " << world << "\n  size_m: " << vec({size.x(), size.y(), size.z()})
    << "\n  texture: noise\n  texture_scale_m: " << num(tex_scale) << "\n  clutter: " << num(clutter) << "\n\n";
  sum << world << " " << g(std::round(size.x() * 10) / 10) << "x" << g(std::round(size.y() * 10) / 10);

  // --- Motion and start.
  std::string motion;
  double speed = 1.0, max_rot = 60.0, max_accel = 1.5, sway = 2.0, bob = 0.015;
  if (world == "street") {
    motion = d.chance(0.8) ? "car" : "drone";
    if (motion == "car") {
      speed = d.uniform(5.0, 12.0), max_rot = d.uniform(30.0, 50.0), max_accel = d.uniform(2.0, 4.0);
      sway = d.uniform(0.2, 0.8), bob = d.uniform(0.0, 0.01);
    } else {
      speed = d.uniform(3.0, 8.0), max_rot = d.uniform(30.0, 90.0), max_accel = d.uniform(1.5, 4.0);
      sway = d.uniform(0.5, 3.0), bob = 0.0;
    }
  } else if (world == "wall") {
    motion = "handheld";
    speed = d.uniform(0.4, 1.2), max_rot = d.uniform(30.0, 70.0), sway = d.uniform(1.0, 3.0), bob = d.uniform(0.005, 0.02);
  } else {
    motion = d.chance(0.7) ? "handheld" : "drone";
    if (motion == "handheld") {
      speed = d.uniform(0.5, 1.6), max_rot = d.uniform(30.0, 90.0), max_accel = d.uniform(1.0, 2.5);
      sway = d.uniform(1.0, 4.0), bob = d.uniform(0.005, 0.03);
    } else {
      speed = d.uniform(1.0, world == "room" ? 2.5 : 4.0), max_rot = d.uniform(30.0, 120.0),
      max_accel = d.uniform(1.5, 4.0), sway = d.uniform(0.5, 3.0), bob = 0.0;
    }
  }
  // Start: at rest long enough for a static window, briefly at rest, or in motion from the first sample.
  const std::size_t start_kind = d.pick({0.4, 0.3, 0.3});
  double static_s = 0.0, ramp_s = 0.0;
  if (start_kind == 0) static_s = d.uniform(1.5, 3.0), ramp_s = d.uniform(0.5, 2.5);
  else if (start_kind == 1) static_s = d.uniform(0.1, 1.5), ramp_s = d.uniform(0.5, 2.5);
  y << "trajectory:\n";
  if (world == "wall") {
    y << "  kind: lissajous\n  size_m: " << vec({d.uniform(0.5, 1.2), d.uniform(2.0, 5.0), d.uniform(0.5, 1.2)})
      << "\n  frequencies: [3, 2, 5]\n  look_at: " << vec({size.x() + 10.0, 0.0, 1.4}) << "\n";
  } else {
    y << "  kind: loop\n";
    if (world == "street") y << "  corner_radius_m: " << num(d.uniform(15.0, 30.0)) << "\n";
    y << "  start_m: " << num(d.uniform(0.0, world == "street" ? 400.0 : 30.0)) << "\n";
  }
  y << "  speed_mps: " << num(speed) << "\n  max_rot_dps: " << num(max_rot) << "\n  max_accel_mps2: " << num(max_accel)
    << "\n  static_s: " << num(static_s) << "\n  ramp_s: " << num(ramp_s) << "\n  sway_deg: " << num(sway)
    << "\n  bob_m: " << num(bob) << "\n\n";

  // --- LiDAR.
  std::string lidar;
  if (world == "street") lidar = std::vector<const char*>{"spinning32", "mid360", "avia"}[d.pick({0.5, 0.3, 0.2})];
  else if (world == "wall") lidar = d.chance(0.6) ? "avia" : "mid360";
  else lidar = std::vector<const char*>{"avia", "mid360", "spinning32"}[d.pick({0.4, 0.4, 0.2})];
  const double model_pps = lidar == "avia" ? 240000.0 : lidar == "mid360" ? 200000.0 : 327680.0;
  const double density = d.logUniform(0.25, 1.0);
  const double lidar_rate = std::vector<double>{10.0, 20.0, 5.0}[d.pick({0.8, 0.1, 0.1})];
  const double range_noise = d.uniform(0.005, 0.03), beam_noise = d.uniform(0.0, 0.1);
  const double blind = d.uniform(0.1, world == "street" ? 2.0 : 1.0);
  const double max_range = world == "street" ? d.uniform(60.0, 150.0) : d.uniform(20.0, 70.0);
  y << "lidar:\n  model: " << lidar << "\n  rate_hz: " << num(lidar_rate) << "\n  points_per_second: "
    << num(std::round(model_pps * density)) << "\n  range_noise_m: " << num(range_noise)
    << "\n  beam_noise_deg: " << num(beam_noise) << "\n  max_range_m: " << num(max_range) << "\n  blind_m: " << num(blind)
    << "\n\n";
  sum << ", " << lidar << " " << g(std::round(model_pps * density / 1000.0)) << "k pts/s @" << g(lidar_rate)
      << " Hz blind " << g(std::round(blind * 100) / 100) << " m";

  // --- IMU: noise from 0.5x to 30x the shipped densities (tactical to consumer grade).
  const double imu_rate = std::vector<double>{100.0, 200.0, 250.0, 400.0}[d.pick({0.2, 0.4, 0.15, 0.25})];
  const double grade = d.logUniform(0.5, 30.0);
  const double gb = d.logUniform(0.0005, 0.01), ab = d.logUniform(0.005, 0.1);
  auto dir = [&d]() {
    Eigen::Vector3d v(d.gaussian(), d.gaussian(), d.gaussian());
    return v.norm() > 1e-9 ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d(Eigen::Vector3d::UnitX());
  };
  const Eigen::Vector3d bg = gb * dir(), ba = ab * dir();
  y << "imu:\n  rate_hz: " << num(imu_rate) << "\n  gyro_noise: " << num(1.7e-4 * grade)
    << "\n  accel_noise: " << num(2.0e-3 * grade) << "\n  gyro_bias_walk: " << num(1.9e-5 * std::sqrt(grade))
    << "\n  accel_bias_walk: " << num(3.0e-3 * std::sqrt(grade)) << "\n  gyro_bias_init: " << vec({bg.x(), bg.y(), bg.z()})
    << "\n  accel_bias_init: " << vec({ba.x(), ba.y(), ba.z()}) << "\n";
  sum << ", IMU " << g(imu_rate) << " Hz x" << g(std::round(grade * 10) / 10) << " noise";
  if (d.chance(0.25)) {  // rotor / engine vibration
    const double va = d.uniform(0.05, 0.5), vg = d.uniform(0.005, 0.05), vf = d.uniform(40.0, 200.0);
    y << "  vibration:\n    accel_mps2: " << num(va) << "\n    gyro_rad_s: " << num(vg) << "\n    freq_hz: " << num(vf)
      << "\n";
    sum << " +vibration";
  }
  y << "\n";

  // --- Camera: at most 8 Mpixel/s rendered (the simulator ray-casts every pixel).
  const bool fisheye = d.chance(0.35);
  static const int kWidths[] = {320, 640, 752, 960, 1280};
  const int width = kWidths[d.pick({0.2, 0.35, 0.15, 0.15, 0.15})];
  const double aspect = std::vector<double>{0.8, 0.75, 0.5625}[d.pick({0.4, 0.4, 0.2})];
  const int height = static_cast<int>(std::lround(width * aspect / 2.0)) * 2;
  std::vector<double> rates{5.0, 10.0, 15.0, 20.0, 30.0};
  double cam_rate = rates[d.pick({0.15, 0.35, 0.15, 0.2, 0.15})];
  while (cam_rate > 5.0 && width * height * cam_rate > 8e6) cam_rate = cam_rate > 10.0 ? cam_rate - 5.0 : 5.0;
  const double fov_deg = fisheye ? d.uniform(120.0, 190.0) : d.uniform(60.0, 110.0);
  const double half = 0.5 * fov_deg * kDeg;
  const double f = fisheye ? (0.5 * width) / half : (0.5 * width) / std::tan(half);
  std::vector<double> dist(4, 0.0);
  if (fisheye) {
    for (double& k : dist) k = d.uniform(-0.02, 0.02);
  } else {
    dist = {d.uniform(-0.3, 0.1), d.uniform(-0.05, 0.1), d.uniform(-1e-3, 1e-3), d.uniform(-1e-3, 1e-3)};
  }
  y << "camera:\n  model: " << (fisheye ? "equidistant" : "pinhole") << "\n  width: " << width << "\n  height: " << height
    << "\n  fx: " << num(f) << "\n  fy: " << num(f * d.uniform(0.995, 1.005)) << "\n  cx: " << num(0.5 * width - 0.5 + d.uniform(-5, 5))
    << "\n  cy: " << num(0.5 * height - 0.5 + d.uniform(-5, 5)) << "\n  distortion: " << vec({dist[0], dist[1], dist[2], dist[3]});
  if (fisheye) y << "\n  max_angle_deg: " << num(std::min(0.5 * fov_deg + 5.0, 100.0));
  y << "\n  rate_hz: " << num(cam_rate) << "\n  phase_s: " << num(d.uniform(0.0, 1.0 / cam_rate))
    << "\n  exposure_jitter: " << num(d.uniform(0.0, 0.3)) << "\n  pixel_noise: " << num(d.uniform(1.0, 4.0));
  sum << ", " << (fisheye ? "fisheye " : "pinhole ") << width << "x" << height << " " << g(std::round(fov_deg))
      << " deg @" << g(cam_rate) << " Hz";
  if (d.chance(0.5)) y << "\n  exposure_time_s: " << num(d.uniform(0.001, std::min(0.02, 0.5 / cam_rate)));
  if (d.chance(0.5)) y << "\n  vignetting: " << num(d.uniform(0.0, 0.5));
  if (d.chance(0.3)) {
    const double t1 = d.uniform(2.0, 0.5 * duration_s), t2 = t1 + d.uniform(1.0, 0.5 * duration_s);
    y << "\n  exposure_steps: " << vec({t1, d.uniform(0.6, 1.6), t2, d.uniform(0.6, 1.6)});
  }
  if (d.chance(0.3)) y << "\n  stamp_delay_s: " << num(d.uniform(0.0, std::min(0.03, 0.5 / cam_rate)));
  y << "\n\n";

  // --- Extrinsics: a few centimetres and up to 3 degrees of tilt off the nominal mounting.
  const Eigen::Vector3d t_l(d.uniform(-0.1, 0.1), d.uniform(-0.1, 0.1),
                            lidar == "spinning32" ? d.uniform(0.1, 0.3) : d.uniform(-0.05, 0.1));
  const Eigen::Quaterniond q_l = smallTilt(d, 3.0);
  const Eigen::Quaterniond q_c0(0.5, -0.5, 0.5, -0.5);  // (w, x, y, z): camera looking along body x
  const Eigen::Vector3d t_c(d.uniform(-0.05, 0.2), d.uniform(-0.1, 0.1), d.uniform(-0.1, 0.1));
  const Eigen::Quaterniond q_c = smallTilt(d, 3.0) * q_c0;
  y << "extrinsics:\n  T_imu_lidar: " << poseText(t_l, q_l) << "\n  T_imu_camera: " << poseText(t_c, q_c) << "\n";

  sum << ", " << motion << " " << g(std::round(speed * 10) / 10) << " m/s, ";
  if (static_s > 0) sum << "rest " << g(std::round(static_s * 10) / 10) << " s";
  else sum << "moving start";
  return {y.str(), sum.str()};
}

}  // namespace livo::sim
