#include "livo/estimation/imu_init.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace livo {

double ImuConfig::gyroSampleSigma() const { return gyro_noise * noise_scale * std::sqrt(rate_hz); }
double ImuConfig::accelSampleSigma() const { return accel_noise * noise_scale * std::sqrt(rate_hz); }

// The RMS deviation of a 3-axis white-noise window is sqrt(3) sigma per sample.
double ImuConfig::staticGyroThreshold() const {
  if (init_max_gyro_std > 0) return init_max_gyro_std;
  return init_static_factor * std::sqrt(3.0) * gyroSampleSigma() + init_vibration_gyro_rad_s;
}

double ImuConfig::staticAccelThreshold() const {
  if (init_max_accel_std > 0) return init_max_accel_std;
  return init_static_factor * std::sqrt(3.0) * accelSampleSigma() + init_vibration_accel_mps2;
}

double ImuConfig::deadlineSeconds() const {
  const double window_s = double(init_samples - 1) / rate_hz;
  return std::max(init_deadline_s, std::max(init_static_wait_s, window_s) + 0.05);
}

bool ImuInitializer::windowStats(WindowStats& w) const {
  const std::size_t n = static_cast<std::size_t>(cfg_.init_samples);
  if (samples_.size() < n) return false;
  const auto begin = samples_.end() - static_cast<std::ptrdiff_t>(n);
  w = WindowStats{};
  w.n = static_cast<int>(n);
  for (auto it = begin; it != samples_.end(); ++it) {
    w.mean_gyro += it->gyro;
    w.mean_accel += it->accel;
  }
  w.mean_gyro /= double(n);
  w.mean_accel /= double(n);
  const double norm_a = w.mean_accel.norm();
  if (!(norm_a > 1e-3) || !std::isfinite(norm_a)) return false;  // no usable gravity
  w.scale = cfg_.gravity_m_s2 / norm_a;
  double var_g = 0, var_a = 0;
  for (auto it = begin; it != samples_.end(); ++it) {
    var_g += (it->gyro - w.mean_gyro).squaredNorm();
    var_a += ((it->accel - w.mean_accel) * w.scale).squaredNorm();
  }
  w.rms_gyro = std::sqrt(var_g / double(n));
  w.rms_accel = std::sqrt(var_a / double(n));
  w.score = std::max(w.rms_gyro / cfg_.staticGyroThreshold(), w.rms_accel / cfg_.staticAccelThreshold());
  // A steady turn has a calm gyro too: at rest the mean rate is the bias, which the prior bounds.
  if (w.mean_gyro.norm() > 5.0 * cfg_.init_gyro_bias_sigma_rad_s) w.score = std::max(w.score, 2.0);
  w.start = begin->utime;
  w.end = samples_.back().utime;
  return std::isfinite(w.score);
}

bool ImuInitializer::add(const ImuSample& s) {
  if (done_) return true;
  if (!samples_.empty() && s.utime <= samples_.back().utime) return false;
  if (first_utime_ < 0) first_utime_ = s.utime;
  samples_.push_back(s);
  const double window_s = double(cfg_.init_samples - 1) / cfg_.rate_hz;
  const double wait_s = std::max(cfg_.init_static_wait_s, window_s);
  // Bounded: the samples after the best window until the decision (at most the wait), or a few
  // windows while none is static.
  const std::size_t cap = static_cast<std::size_t>(4.0 * (cfg_.init_samples + wait_s * cfg_.rate_hz)) + 16;
  while (samples_.size() > cap && (!have_best_ || samples_.front().utime < best_.end)) samples_.pop_front();

  WindowStats w;
  const bool full = windowStats(w);
  if (full) last_ = w;
  const bool is_static = full && w.score < 1.0;
  if (is_static && (!have_best_ || w.score < best_.score)) {
    best_ = w;
    have_best_ = true;
  }
  const bool waited = toSeconds(s.utime - first_utime_) >= wait_s;
  // The calm ended (a window in motion after a static one) or the wait is over: take the calmest.
  if (have_best_ && ((full && !is_static) || waited)) {
    choose(best_);
    return true;
  }
  if (waited && !have_best_) no_static_ = true;
  return false;
}

void ImuInitializer::choose(const WindowStats& w) {
  accel_scale_ = w.scale;
  state_ = NavState();
  state_.utime = w.end;
  state_.bg = w.mean_gyro;
  // Gravity: the accelerometer at rest measures -g in the body frame (specific force).
  const Vec3 up_body = w.mean_accel.normalized();
  if (cfg_.gravity_align) {
    // R_world_imu with R * up_body = +z and no yaw component (shortest rotation).
    state_.R_world_imu = Quat::FromTwoVectors(up_body, Vec3::UnitZ()).toRotationMatrix();
    state_.g_world = Vec3(0, 0, -cfg_.gravity_m_s2);
  } else {
    state_.R_world_imu = Mat3::Identity();
    state_.g_world = -up_body * cfg_.gravity_m_s2;
  }
  best_ = w;
  done_ = true;
  no_static_ = false;
}

void ImuInitializer::reject() {
  done_ = false;
  have_best_ = false;
  no_static_ = true;
  // The windows up to now moved: only windows that start after now count.
  while (samples_.size() > 1) samples_.pop_front();
}

StateCov ImuInitializer::prior(const Mat3& R, double var_tilt, double var_bg) const {
  StateCov P = ::livo::initialCovariance();
  using namespace sidx;
  P.block<3, 3>(kBg, kBg) = Mat3::Identity() * var_bg;
  // The rotation error is in the body frame: R^T diag(tilt, tilt, yaw) R (a small yaw floor keeps P
  // positive definite).
  P.block<3, 3>(kRot, kRot) = R.transpose() * Vec3(var_tilt, var_tilt, 1e-8).asDiagonal() * R;
  P.block<3, 3>(kBa, kBa) = Mat3::Identity() * cfg_.init_accel_bias_sigma_mps2 * cfg_.init_accel_bias_sigma_mps2;
  return P;
}

StateCov ImuInitializer::initialCovariance() const {
  const double n = double(std::max(1, best_.n));
  const double window_s = double(best_.n) / cfg_.rate_hz;
  // Gyro bias: the mean of n samples, plus the walk over the window.
  const double var_bg = cfg_.gyroSampleSigma() * cfg_.gyroSampleSigma() / n +
                        cfg_.gyro_bias_walk * cfg_.gyro_bias_walk * window_s;
  // Roll and pitch from the mean specific force, as well as the accelerometer bias allows (at rest a
  // horizontal bias and a tilt look the same); yaw is the world's definition.
  const double sigma_mean = cfg_.accelSampleSigma() / std::sqrt(n);
  const double sigma_ba = cfg_.init_accel_bias_sigma_mps2;
  const double var_tilt = std::max((sigma_mean * sigma_mean + sigma_ba * sigma_ba) / (cfg_.gravity_m_s2 * cfg_.gravity_m_s2), 1e-8);
  return prior(state_.R_world_imu, var_tilt, var_bg);
}

bool ImuInitializer::coarseState(NavState& x, StateCov& P, double& tilt_sigma_rad, double& accel_scale) const {
  if (samples_.empty()) return false;
  // The mean specific force over the last second: gravity plus the mean acceleration (a velocity
  // change over that second), whose size bounds the tilt error.
  const Utime t_end = samples_.back().utime;
  Vec3 mean = Vec3::Zero(), mean_g = Vec3::Zero();
  int n = 0;
  for (auto it = samples_.rbegin(); it != samples_.rend() && toSeconds(t_end - it->utime) <= 1.0; ++it, ++n) {
    mean += it->accel;
    mean_g += it->gyro;
  }
  mean /= double(n);
  mean_g /= double(n);
  const double norm = mean.norm();
  if (!(norm > 1e-3) || !std::isfinite(norm)) return false;
  accel_scale = norm < 4.0 ? cfg_.gravity_m_s2 / norm : 1.0;  // g units or m/s^2
  double var = 0;
  for (auto it = samples_.rbegin(); it != samples_.rend() && toSeconds(t_end - it->utime) <= 1.0; ++it)
    var += ((it->accel - mean) * accel_scale).squaredNorm();
  const double rms = std::sqrt(var / double(n));
  x = NavState();
  x.utime = t_end;
  const Vec3 up_body = mean.normalized();
  if (cfg_.gravity_align) {
    x.R_world_imu = Quat::FromTwoVectors(up_body, Vec3::UnitZ()).toRotationMatrix();
    x.g_world = Vec3(0, 0, -cfg_.gravity_m_s2);
  } else {
    x.g_world = -up_body * cfg_.gravity_m_s2;
  }
  // A calm window says more about the gyro bias than the prior: its mean rate, when plausible.
  if (mean_g.norm() < 3.0 * cfg_.init_gyro_bias_sigma_rad_s) x.bg = mean_g;
  // Tilt: the mean acceleration over the second is at most about the RMS deviation (a steady push is
  // rare in a handheld or vehicle start); between 2 and 15 degrees.
  tilt_sigma_rad = std::clamp(std::atan2(std::max(rms, std::abs(norm * accel_scale - cfg_.gravity_m_s2)), cfg_.gravity_m_s2),
                              2.0 * M_PI / 180.0, 15.0 * M_PI / 180.0);
  P = prior(x.R_world_imu, tilt_sigma_rad * tilt_sigma_rad,
            cfg_.init_gyro_bias_sigma_rad_s * cfg_.init_gyro_bias_sigma_rad_s);
  return true;
}

std::string ImuInitializer::status() const {
  std::ostringstream os;
  os.precision(3);
  const double window_s = double(cfg_.init_samples) / cfg_.rate_hz;
  if (done_) {
    os << "static window found (" << best_.n << " samples), waiting for the LiDAR to confirm the rest";
  } else if (last_.n == 0) {
    os << "collecting the first static window of " << cfg_.init_samples << " samples (" << window_s << " s)";
  } else {
    os << "no static window of " << cfg_.init_samples << " samples yet: gyro RMS " << last_.rms_gyro << " rad/s of "
       << cfg_.staticGyroThreshold() << " allowed, accel RMS " << last_.rms_accel << " m/s^2 of "
       << cfg_.staticAccelThreshold() << " allowed";
    if (last_.mean_gyro.norm() > 5.0 * cfg_.init_gyro_bias_sigma_rad_s)
      os << ", mean rate " << last_.mean_gyro.norm() << " rad/s (turning)";
  }
  return os.str();
}

std::vector<ImuSample> ImuInitializer::samplesAfterWindow() const {
  std::vector<ImuSample> out;
  for (const auto& s : samples_)
    if (s.utime > best_.end) out.push_back(s);
  return out;
}

std::string ImuInitializer::describe() const {
  std::ostringstream os;
  os << "IMU initialised at rest from " << best_.n << " samples (RMS deviation gyro " << best_.rms_gyro
     << " rad/s of " << cfg_.staticGyroThreshold() << " allowed, accel " << best_.rms_accel << " m/s^2 of "
     << cfg_.staticAccelThreshold() << ")"
     << ", accel scale " << accel_scale_ << (std::abs(accel_scale_ - 1.0) > 0.2 ? " (g units detected)" : "")
     << ", gyro bias [" << state_.bg.transpose() << "] rad/s";
  return os.str();
}

}  // namespace livo
