// Random rigs: the distribution of config/sim/README.md, section "Random rigs".
#include "livo/sim/random_scenario.hpp"

#include "livo/common/so3.hpp"
#include "livo/sim/random.hpp"
#include "livo/sim/trajectory.hpp"

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

double aliasedHz(double freq_hz, double rate_hz) {
  return std::abs(freq_hz - rate_hz * std::round(freq_hz / rate_hz));
}

RandomScenario drawRandomScenario(std::uint64_t seed, double duration_s) {
  Draw d(seed);
  std::ostringstream y, sum;
  std::vector<std::string> classes;
  y << "seed: " << (seed % 1000000007ull) << "\n"
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
  // Start: at rest for a while; briefly at rest; a fast start (under half a second
  // at rest, then up to cruise at the vehicle's acceleration limit: the quintic ramp's peak
  // acceleration is kRampPeak x cruise / ramp_s); or in motion at cruise from the first sample.
  constexpr double kRampPeak = 1.875;  // max of h'(x) = 30 x^2 (1 - x)^2 (trajectory.cpp)
  const std::size_t start_kind = d.pick({0.35, 0.15, 0.2, 0.3});
  double static_s = 0.0, ramp_s = 0.0;
  if (start_kind == 0) static_s = d.uniform(1.5, 3.0), ramp_s = d.uniform(0.5, 2.5);
  else if (start_kind == 1) static_s = d.uniform(0.5, 1.5), ramp_s = d.uniform(0.5, 2.5);
  else if (start_kind == 2) static_s = d.uniform(0.05, 0.5), ramp_s = kRampPeak * speed / max_accel;
  y << "trajectory:\n  motion: " << motion << "\n";
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
  if (start_kind == 3) classes.push_back("moving-start");
  if (start_kind == 2) classes.push_back("fast-start");

  // --- LiDAR: the same models in every world (spinning ones on walls and in rooms as on streets).
  const std::string lidar = std::vector<const char*>{"avia", "mid360", "spinning32"}[d.pick({1.0, 1.0, 1.0})];
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
  if (lidar == "spinning32" && (world == "wall" || world == "room")) classes.push_back("spinning-" + world);

  // --- IMU: noise from 0.5x to 30x the shipped densities (tactical to consumer grade), bias walks
  // 0.5x to 10x the shipped ones (drawn apart from the noise and from each other).
  const double imu_rate = std::vector<double>{100.0, 200.0, 250.0, 400.0}[d.pick({0.2, 0.4, 0.15, 0.25})];
  const double grade = d.logUniform(0.5, 30.0);
  const double gyro_walk = d.logUniform(0.5, 10.0), accel_walk = d.logUniform(0.5, 10.0);
  const double gb = d.logUniform(0.0005, 0.01), ab = d.logUniform(0.005, 0.1);
  auto dir = [&d]() {
    Eigen::Vector3d v(d.gaussian(), d.gaussian(), d.gaussian());
    return v.norm() > 1e-9 ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d(Eigen::Vector3d::UnitX());
  };
  const Eigen::Vector3d bg = gb * dir(), ba = ab * dir();
  y << "imu:\n  rate_hz: " << num(imu_rate) << "\n  gyro_noise: " << num(1.7e-4 * grade)
    << "\n  accel_noise: " << num(2.0e-3 * grade) << "\n  gyro_bias_walk: " << num(1.9e-5 * gyro_walk)
    << "\n  accel_bias_walk: " << num(3.0e-3 * accel_walk) << "\n  gyro_bias_init: " << vec({bg.x(), bg.y(), bg.z()})
    << "\n  accel_bias_init: " << vec({ba.x(), ba.y(), ba.z()}) << "\n";
  sum << ", IMU " << g(imu_rate) << " Hz x" << g(std::round(grade * 10) / 10) << " noise, walk x"
      << g(std::round(gyro_walk * 10) / 10) << " / x" << g(std::round(accel_walk * 10) / 10);
  if (grade > 10.0) classes.push_back("noisy-imu");
  // Rotor / engine vibration, sampled by the IMU at its rate without an anti-aliasing filter: above
  // half the rate it shows at the aliased frequency.
  if (d.chance(0.3)) {
    const double va = d.logUniform(0.05, 3.0), vg = d.logUniform(0.005, 0.06), vf = d.uniform(20.0, 250.0);
    y << "  vibration:\n    accel_mps2: " << num(va) << "\n    gyro_rad_s: " << num(vg) << "\n    freq_hz: " << num(vf)
      << "\n";
    sum << ", vibration " << g(std::round(va * 100) / 100) << " m/s^2 " << g(std::round(vg * 1000) / 1000) << " rad/s at "
        << g(std::round(vf)) << " Hz";
    if (vf > 0.5 * imu_rate) {
      sum << " (aliased to " << g(std::round(aliasedHz(vf, imu_rate) * 10) / 10) << " Hz by the " << g(imu_rate)
          << " Hz IMU)";
      classes.push_back("vibration-aliased");
    } else {
      sum << " (under the " << g(imu_rate) << " Hz IMU's Nyquist " << g(0.5 * imu_rate) << " Hz)";
      classes.push_back("vibration");
    }
  }
  y << "\n";

  // --- Camera: 0.5 to 3 times the LiDAR's rate; at most 8 Mpixel/s rendered (the simulator ray-casts
  // every pixel): a faster camera gets fewer pixels.
  const bool fisheye = d.chance(0.35);
  static const int kWidths[] = {320, 640, 752, 960, 1280};
  std::size_t width_i = d.pick({0.2, 0.35, 0.15, 0.15, 0.15});
  const double aspect = std::vector<double>{0.8, 0.75, 0.5625}[d.pick({0.4, 0.4, 0.2})];
  const double cam_factor = std::vector<double>{0.5, 1.0, 1.5, 2.0, 3.0}[d.pick({0.15, 0.35, 0.15, 0.2, 0.15})];
  const double cam_rate = cam_factor * lidar_rate;
  auto heightOf = [aspect](int w) { return static_cast<int>(std::lround(w * aspect / 2.0)) * 2; };
  while (width_i > 0 && kWidths[width_i] * heightOf(kWidths[width_i]) * cam_rate > 8e6) --width_i;
  const int width = kWidths[width_i], height = heightOf(width);
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
      << " deg @" << g(cam_rate) << " Hz (" << g(cam_factor) << "x the LiDAR)";
  if (cam_factor >= 2.0) classes.push_back("fast-camera");
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
  if (start_kind == 0) {
    sum << "rest " << g(std::round(static_s * 10) / 10) << " s then a " << g(std::round(ramp_s * 10) / 10) << " s ramp";
  } else if (start_kind == 1) {
    sum << "short rest " << g(std::round(static_s * 10) / 10) << " s then a " << g(std::round(ramp_s * 10) / 10)
        << " s ramp";
  } else if (start_kind == 2) {
    sum << "short rest " << g(std::round(static_s * 100) / 100) << " s then " << g(std::round(max_accel * 10) / 10)
        << " m/s^2 acceleration";
  } else {
    // The speed at the first sample: the cruise limit, or less where the start lies in a turn.
    double v0 = speed;
    try {
      const SimScenario sc = parseScenario(y.str());
      v0 = SimTrajectory(sc.trajectory, sc.world).state(0.0).v_world.norm();
    } catch (const ConfigError&) {
    }
    sum << "moving at " << g(std::round(v0 * 10) / 10) << " m/s from the first sample";
  }
  std::string class_list;
  for (const auto& c : classes) class_list += (class_list.empty() ? "" : ", ") + c;
  if (!classes.empty()) sum << " [" << class_list << "]";
  std::ostringstream head;
  head << "# Random rig " << seed << " (livo-sim --random " << seed
       << "): drawn from the distribution of config/sim/README.md, section \"Random rigs\".\n"
       << "# classes: " << (classes.empty() ? "-" : class_list) << "\n";
  return {head.str() + y.str(), sum.str(), classes};
}

}  // namespace livo::sim
