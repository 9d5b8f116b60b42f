#include "livo/estimation/imu.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace livo {

void ImuConfig::load(const ConfigNode& n, double imu_rate_hz) {
  rate_hz = imu_rate_hz;
  n.get("gyro_noise", gyro_noise).get("accel_noise", accel_noise);
  n.get("gyro_bias_walk", gyro_bias_walk).get("accel_bias_walk", accel_bias_walk);
  n.get("noise_scale", noise_scale).get("inv_exposure_walk", inv_exposure_walk);
  n.get("gravity_m_s2", gravity_m_s2).get("gravity_align", gravity_align);
  n.get("init_samples", init_samples).get("init_speed_sigma_mps", init_speed_sigma_mps);
  n.check(!n.has("init_max_samples"), "init_max_samples",
          "was removed on 2026-12-01: the filter starts once init_samples samples are in; delete the key");
  // The start rules' keys (removed on 2026-12-07, docs/contract-changes.md): harmless, so read and
  // named rather than refused (configs written before still load).
  ignored_keys.clear();
  for (const char* key : {"init_static_factor", "init_vibration_gyro_rad_s", "init_vibration_accel_mps2",
                          "init_max_gyro_std", "init_max_accel_std", "init_static_wait_s", "init_deadline_s", "start",
                          "init_motion_rot_sigma_deg", "init_motion_pos_sigma_m", "init_motion_min_updates",
                          "init_motion_max_speed_sigma_mps", "init_motion_max_tilt_sigma_deg",
                          "init_motion_max_window_s", "init_motion_max_speed_mps"}) {
    if (!n.has(key)) continue;
    std::string ignored;
    n.get(key, ignored);
    ignored_keys.push_back(n.path() + "." + key);
  }
  n.get("init_gyro_bias_sigma_rad_s", init_gyro_bias_sigma_rad_s).get("init_accel_bias_sigma_mps2", init_accel_bias_sigma_mps2);
  // Densities: positive (a zero density makes every covariance singular) and below values no real
  // IMU has (units: the key's; a typo of the unit, e.g. deg for rad, lands there).
  const auto positiveBelow = [&](const char* key, double v, double max) {
    n.check(std::isfinite(v) && v > 0 && v < max, key,
            "must be > 0 and < " + std::to_string(max) + " (a continuous-time noise density), got " + std::to_string(v));
  };
  positiveBelow("gyro_noise", gyro_noise, 1.0);
  positiveBelow("accel_noise", accel_noise, 10.0);
  positiveBelow("gyro_bias_walk", gyro_bias_walk, 1.0);
  positiveBelow("accel_bias_walk", accel_bias_walk, 10.0);
  n.check(noise_scale > 0 && noise_scale < 1e3, "noise_scale", "must be in (0, 1000)");
  n.check(init_samples >= 5, "init_samples", "must be >= 5");
  n.check(gravity_m_s2 > 5 && gravity_m_s2 < 15, "gravity_m_s2", "must be about 9.8");
  n.check(init_speed_sigma_mps > 0 && init_speed_sigma_mps < 100, "init_speed_sigma_mps", "must be in (0, 100) m/s");
  n.check(init_gyro_bias_sigma_rad_s > 0 && init_gyro_bias_sigma_rad_s < 1, "init_gyro_bias_sigma_rad_s", "must be in (0, 1) rad/s");
  n.check(init_accel_bias_sigma_mps2 > 0 && init_accel_bias_sigma_mps2 < 5, "init_accel_bias_sigma_mps2", "must be in (0, 5) m/s^2");
}

// ---------------- propagation ----------------

StateCov ImuPropagator::transition(const NavState& x, const Vec3& gyro, const Vec3& accel, double dt) const {
  const Vec3 w = gyro - x.bg;                 // unbiased rate
  const Vec3 a = accel * accel_scale_ - x.ba;  // unbiased specific force
  const Mat3& R0 = x.R_world_imu;
  // Identity except the blocks below, evaluated at the interval start.
  StateCov F = StateCov::Identity();
  using namespace sidx;
  F.block<3, 3>(kRot, kRot) = expSO3(-w * dt);
  F.block<3, 3>(kRot, kBg) = -rightJacobianSO3(w * dt) * dt;
  F.block<3, 3>(kPos, kVel) = Mat3::Identity() * dt;
  F.block<3, 3>(kPos, kRot) = -0.5 * R0 * hat(a) * dt * dt;
  F.block<3, 3>(kPos, kBa) = -0.5 * R0 * dt * dt;
  F.block<3, 3>(kPos, kGrav) = 0.5 * Mat3::Identity() * dt * dt;
  F.block<3, 3>(kVel, kRot) = -R0 * hat(a) * dt;
  F.block<3, 3>(kVel, kBa) = -R0 * dt;
  F.block<3, 3>(kVel, kGrav) = Mat3::Identity() * dt;
  return F;
}

void ImuPropagator::step(NavState& x, StateCov& P, const Vec3& gyro, const Vec3& accel, double dt,
                         ImuTracePoint* tp) const {
  const Vec3 w = gyro - x.bg;                 // unbiased rate
  const Vec3 a = accel * accel_scale_ - x.ba;  // unbiased specific force
  const Mat3 R0 = x.R_world_imu;
  const StateCov F = transition(x, gyro, accel, dt);
  using namespace sidx;

  // Discretised continuous-time noise densities (variance = density^2 * dt).
  const double s = cfg_.noise_scale * cfg_.noise_scale;
  StateCov Q = StateCov::Zero();
  Q.block<3, 3>(kRot, kRot).diagonal().setConstant(s * cfg_.gyro_noise * cfg_.gyro_noise * dt);
  Q.block<3, 3>(kVel, kVel).diagonal().setConstant(s * cfg_.accel_noise * cfg_.accel_noise * dt);
  Q.block<3, 3>(kPos, kPos).diagonal().setConstant(s * cfg_.accel_noise * cfg_.accel_noise * dt * dt * dt / 3.0);
  Q.block<3, 3>(kBg, kBg).diagonal().setConstant(s * cfg_.gyro_bias_walk * cfg_.gyro_bias_walk * dt);
  Q.block<3, 3>(kBa, kBa).diagonal().setConstant(s * cfg_.accel_bias_walk * cfg_.accel_bias_walk * dt);
  Q(kExposure, kExposure) = cfg_.inv_exposure_walk * cfg_.inv_exposure_walk * dt;
  P = F * P * F.transpose() + Q;

  // Nominal state: constant rate and world acceleration over the interval.
  const Vec3 acc_world = R0 * a + x.g_world;
  if (tp) {
    tp->utime = x.utime;
    tp->R_world_imu = R0;
    tp->p_world_imu = x.p_world_imu;
    tp->v_world = x.v_world;
    tp->acc_world = acc_world;
    tp->omega = w;
  }
  x.p_world_imu += x.v_world * dt + 0.5 * acc_world * dt * dt;
  x.v_world += acc_world * dt;
  x.R_world_imu = R0 * expSO3(w * dt);
}

void ImuPropagator::propagate(NavState& x, StateCov& P, const std::vector<ImuSample>& samples, Utime t_end,
                              std::vector<ImuTracePoint>* trace) const {
  if (trace) trace->clear();
  if (samples.empty() || t_end <= x.utime) {
    if (trace) {
      ImuTracePoint tp;
      tp.utime = x.utime;
      tp.R_world_imu = x.R_world_imu;
      tp.p_world_imu = x.p_world_imu;
      tp.v_world = x.v_world;
      trace->push_back(tp);
    }
    return;
  }
  // Cut [x.utime, t_end] at every sample time inside it. Each segment uses the mid-point mean of the
  // two samples around it; before the first sample and after the last one the nearest sample is held.
  std::vector<Utime> cuts{x.utime};
  for (const auto& smp : samples)
    if (smp.utime > cuts.back() && smp.utime < t_end) cuts.push_back(smp.utime);
  cuts.push_back(t_end);
  std::size_t k = 0;
  for (std::size_t j = 0; j + 1 < cuts.size(); ++j) {
    const Utime ta = cuts[j], tb = cuts[j + 1];
    while (k + 1 < samples.size() && samples[k + 1].utime <= ta) ++k;
    const ImuSample& a = samples[k];
    const ImuSample& b = (k + 1 < samples.size() && a.utime <= ta) ? samples[k + 1] : a;
    ImuTracePoint tp;
    step(x, P, 0.5 * (a.gyro + b.gyro), 0.5 * (a.accel + b.accel), toSeconds(tb - ta), trace ? &tp : nullptr);
    if (trace) trace->push_back(tp);
    x.utime = tb;
  }
  if (trace) {
    ImuTracePoint end;
    end.utime = x.utime;
    end.R_world_imu = x.R_world_imu;
    end.p_world_imu = x.p_world_imu;
    end.v_world = x.v_world;
    if (!trace->empty()) {
      end.acc_world = trace->back().acc_world;
      end.omega = trace->back().omega;
    }
    trace->push_back(end);
  }
}

Pose ImuPropagator::poseAt(const std::vector<ImuTracePoint>& trace, Utime t) {
  Pose T = Pose::Identity();
  if (trace.empty()) return T;
  // Last trace point with utime <= t (or the first one when t precedes the trace).
  auto it = std::upper_bound(trace.begin(), trace.end(), t,
                             [](Utime v, const ImuTracePoint& tp) { return v < tp.utime; });
  const ImuTracePoint& k = (it == trace.begin()) ? trace.front() : *(it - 1);
  const double dt = toSeconds(t - k.utime);
  T.linear() = k.R_world_imu * expSO3(k.omega * dt);
  T.translation() = k.p_world_imu + k.v_world * dt + 0.5 * k.acc_world * dt * dt;
  return T;
}

}  // namespace livo
