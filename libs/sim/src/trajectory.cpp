// Evaluation half of SimTrajectory: spline, time warp, sway and the body state (trajectory.hpp).
#include "livo/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace livo::sim {

namespace {

constexpr double kTwoPi = 6.283185307179586;

// Sway: per axis, two sines (relative amplitude, frequency Hz, phase rad); the axis amplitude is
// sway_deg times kSwayAxisGain. Frequencies are incommensurate so the motion never repeats exactly.
struct Sine {
  double amp, hz, phase;
};
constexpr Sine kRoll[2] = {{0.7, 0.63, 0.3}, {0.3, 1.37, 1.1}};
constexpr Sine kPitch[2] = {{0.6, 0.91, 0.5}, {0.4, 0.41, 2.0}};
constexpr Sine kYaw[2] = {{0.5, 0.29, 1.7}, {0.5, 0.83, 0.4}};
constexpr double kSwayAxisGain[3] = {1.0, 0.8, 0.5};  // roll, pitch, yaw
constexpr double kBobHz = 1.7;                        // walking step frequency

// Quintic smoothstep h(x) = 6x^5 - 15x^4 + 10x^3 (C2: h, h', h'' vanish at 0; h', h'' at 1), its
// integral H and derivatives.
inline double h(double x) { return x * x * x * (x * (6.0 * x - 15.0) + 10.0); }
inline double dh(double x) { return 30.0 * x * x * (x - 1.0) * (x - 1.0); }
inline double ddh(double x) { return 60.0 * x * (2.0 * x * x - 3.0 * x + 1.0); }
inline double H(double x) { return x * x * x * x * (x * (x - 3.0) + 2.5); }

void sines(const Sine (&s)[2], double t, double& f, double& df) {
  f = df = 0.0;
  for (const Sine& k : s) {
    const double w = kTwoPi * k.hz;
    f += k.amp * std::sin(w * t + k.phase);
    df += k.amp * w * std::cos(w * t + k.phase);
  }
}

Mat3 rotX(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }
Mat3 rotY(double a) { return Eigen::AngleAxisd(a, Vec3::UnitY()).toRotationMatrix(); }
Mat3 rotZ(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }

}  // namespace

double swayRateBound(double amplitude_rad) {
  double sq = 0.0;
  const Sine* axes[3] = {kRoll, kPitch, kYaw};
  for (int a = 0; a < 3; ++a) {
    double r = 0.0;
    for (int k = 0; k < 2; ++k) r += axes[a][k].amp * kTwoPi * axes[a][k].hz;
    r *= amplitude_rad * kSwayAxisGain[a];
    sq += r * r;
  }
  return std::sqrt(sq);
}

// Periodic uniform cubic B-spline: segment i (tau in [i dt, (i+1) dt)) blends c[i-1], c[i], c[i+1],
// c[i+2] with the uniform basis (so P(i dt) = (c[i-1] + 4 c[i] + c[i+1]) / 6); derivatives by tau.
SimTrajectory::SplineEval SimTrajectory::spline(double tau) const {
  const auto n = static_cast<long long>(ctrl_.size());
  const double u = tau / knot_dt_;
  const double fu = std::floor(u);
  const double x = u - fu;
  const long long i = static_cast<long long>(fu);
  auto c = [&](long long k) -> const Vec3& { return ctrl_[static_cast<std::size_t>(((k % n) + n) % n)]; };
  const Vec3 &c0 = c(i - 1), &c1 = c(i), &c2 = c(i + 1), &c3 = c(i + 2);
  const double x2 = x * x, x3 = x2 * x, mx = 1.0 - x;
  SplineEval e;
  e.p = (mx * mx * mx * c0 + (3.0 * x3 - 6.0 * x2 + 4.0) * c1 + (-3.0 * x3 + 3.0 * x2 + 3.0 * x + 1.0) * c2 + x3 * c3) / 6.0;
  e.dp = (-3.0 * mx * mx * c0 + (9.0 * x2 - 12.0 * x) * c1 + (-9.0 * x2 + 6.0 * x + 3.0) * c2 + 3.0 * x2 * c3) /
         (6.0 * knot_dt_);
  e.ddp = (6.0 * mx * c0 + (18.0 * x - 12.0) * c1 + (-18.0 * x + 6.0) * c2 + 6.0 * x * c3) / (6.0 * knot_dt_ * knot_dt_);
  return e;
}

// tau(t): 0 while static, then dtau/dt = c h(x) over the ramp (x = (t - t_s) / T_r), then c. A start in
// motion (static_s = ramp_s = 0) is at cruise at t = 0 too, not at rest for its first instant.
void SimTrajectory::timeWarp(double t, double& tau, double& dtau, double& ddtau) const {
  const double ts = cfg_.static_s, tr = cfg_.ramp_s, c = time_scale_;
  if (t <= ts && !(ts == 0.0 && tr == 0.0)) {
    tau = dtau = ddtau = 0.0;
  } else if (t < ts + tr) {
    const double x = (t - ts) / tr;
    tau = c * tr * H(x);
    dtau = c * h(x);
    ddtau = c * dh(x) / tr;
  } else {
    tau = c * tr * 0.5 + c * (t - ts - tr);  // H(1) = 1/2
    dtau = c;
    ddtau = 0.0;
  }
}

// Sway angles (roll, pitch, yaw) and their rates, and the bob height with two derivatives, each
// multiplied by the ramp factor g(t) (0 at rest, 1 at cruise, C2).
void SimTrajectory::sway(double t, Vec3& angles, Vec3& rates, double& z, double& dz, double& ddz) const {
  double g = 0.0, dg = 0.0, ddg = 0.0;
  const double ts = cfg_.static_s, tr = cfg_.ramp_s;
  if (t >= ts + tr) g = 1.0;
  else if (t > ts) {
    const double x = (t - ts) / tr;
    g = h(x);
    dg = dh(x) / tr;
    ddg = ddh(x) / (tr * tr);
  }
  const double amp = *cfg_.sway_deg * kTwoPi / 360.0;  // set by withDefaults (path.cpp)
  const Sine(*axes[3])[2] = {&kRoll, &kPitch, &kYaw};
  for (int a = 0; a < 3; ++a) {
    double f, df;
    sines(*axes[a], t, f, df);
    const double A = amp * kSwayAxisGain[a];
    angles[a] = A * g * f;
    rates[a] = A * (dg * f + g * df);
  }
  const double w = kTwoPi * kBobHz;
  const double s = std::sin(w * t), c = std::cos(w * t);
  const double bob = *cfg_.bob_m;
  z = bob * g * s;
  dz = bob * (dg * s + g * w * c);
  ddz = bob * (ddg * s + 2.0 * dg * w * c - g * w * w * s);
}

BodyState SimTrajectory::state(double t) const {
  t = std::max(t, 0.0);
  double tau, dtau, ddtau;
  timeWarp(t, tau, dtau, ddtau);
  const SplineEval e = spline(tau);
  Vec3 ang, rate;
  double z, dz, ddz;
  sway(t, ang, rate, z, dz, ddz);

  BodyState s;
  const Vec3 p = e.p + Vec3(0.0, 0.0, z);
  // Chain rule through tau(t): v = P' tau', a = P'' tau'^2 + P' tau''.
  s.v_world = e.dp * dtau + Vec3(0.0, 0.0, dz);
  s.a_world = e.ddp * dtau * dtau + e.dp * ddtau + Vec3(0.0, 0.0, ddz);

  // Heading: the path tangent (d/dt atan2(P'y, P'x) = (P' x P'')_z / |P'_xy|^2 * tau'), or facing the
  // target (d = target - p, d' = -v).
  double yaw, dyaw;
  if (look_at_) {
    const double dx = target_.x() - p.x(), dy = target_.y() - p.y();
    yaw = std::atan2(dy, dx);
    dyaw = (dx * -s.v_world.y() - dy * -s.v_world.x()) / (dx * dx + dy * dy);
  } else {
    yaw = std::atan2(e.dp.y(), e.dp.x());
    dyaw = (e.dp.x() * e.ddp.y() - e.dp.y() * e.ddp.x()) / (e.dp.x() * e.dp.x() + e.dp.y() * e.dp.y()) * dtau;
  }
  const double roll = ang[0], pitch = cfg_.pitch_deg * kTwoPi / 360.0 + ang[1];
  yaw += ang[2];
  dyaw += rate[2];

  // R = Rz(yaw) Ry(pitch) Rx(roll); body rate = Rx^T Ry^T (yaw' e_z) + Rx^T (pitch' e_y) + roll' e_x.
  const Mat3 Rx = rotX(roll), Ry = rotY(pitch), Rz = rotZ(yaw);
  s.T_world_imu.setIdentity();
  s.T_world_imu.linear() = Rz * Ry * Rx;
  s.T_world_imu.translation() = p;
  s.omega_body = Rx.transpose() * (Ry.transpose() * Vec3(0.0, 0.0, dyaw) + Vec3(0.0, rate[1], 0.0)) +
                 Vec3(rate[0], 0.0, 0.0);
  return s;
}

void SimTrajectory::measurePeaks() {
  peak_speed_ = peak_rate_ = 0.0;
  const double end = cfg_.static_s + cfg_.ramp_s + lapTime() + 5.0;
  const double step = std::min(0.01, knot_dt_ / 8.0);
  // From the first step on: the grid is a sampling either way, and t = 0 of a start in motion (the
  // limit of the states after it) left out keeps the timing the scenarios had before it counted.
  for (double t = step; t <= end; t += step) {
    const BodyState s = state(t);
    peak_speed_ = std::max(peak_speed_, s.v_world.norm());
    peak_rate_ = std::max(peak_rate_, s.omega_body.norm());
  }
  peak_speed_ = std::max(peak_speed_, 1e-9);
  peak_rate_ = std::max(peak_rate_, 1e-9);
}

}  // namespace livo::sim
