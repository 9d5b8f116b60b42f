#include "livo/estimation/imu_init.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace livo {

namespace {

/// The span of one window of init_samples samples.
double windowSeconds(const ImuConfig& cfg) { return double(cfg.init_samples - 1) / cfg.rate_hz; }

/// Gravity is averaged over at most this long (the samples kept).
constexpr double kGravitySeconds = 1.0;
/// The start's tilt sigma is kept within these: a few tenths of m/s^2 of push hide in an IMU's noise and
/// scale error (the floor), and beyond 15 degrees the error-state linearisation is poor anyway.
constexpr double kMinTilt = 2.0 * M_PI / 180.0;
constexpr double kMaxTilt = 15.0 * M_PI / 180.0;

}  // namespace

bool ImuInitializer::add(const ImuSample& s) {
  if (!samples_.empty() && s.utime <= samples_.back().utime) return ready();
  if (first_utime_ < 0) first_utime_ = s.utime;
  samples_.push_back(s);
  const double keep_s = std::max(kGravitySeconds, windowSeconds(cfg_));
  while (samples_.size() > 1 && toSeconds(s.utime - samples_.front().utime) > keep_s) samples_.pop_front();
  return ready();
}

bool ImuInitializer::ready() const {
  return first_utime_ >= 0 && toSeconds(samples_.back().utime - first_utime_) >= windowSeconds(cfg_);
}

bool ImuInitializer::start(NavState& x, StateCov& P, double& tilt_sigma_rad, double& accel_scale) const {
  if (samples_.empty()) return false;
  Vec3 mean = Vec3::Zero(), mean_g = Vec3::Zero();
  for (const auto& s : samples_) {
    mean += s.accel;
    mean_g += s.gyro;
  }
  const double n = double(samples_.size());
  mean /= n;
  mean_g /= n;
  const double norm = mean.norm();
  if (!(norm > 1e-3) || !std::isfinite(norm)) return false;
  accel_scale = norm < 4.0 ? cfg_.gravity_m_s2 / norm : 1.0;  // g units or m/s^2
  double var = 0;
  for (const auto& s : samples_) var += ((s.accel - mean) * accel_scale).squaredNorm();
  const double rms = std::sqrt(var / n);
  x = NavState();
  x.utime = samples_.back().utime;
  const Vec3 up_body = mean.normalized();
  if (cfg_.gravity_align) {
    // R_world_imu with R * up_body = +z and no yaw component (shortest rotation).
    x.R_world_imu = Quat::FromTwoVectors(up_body, Vec3::UnitZ()).toRotationMatrix();
    x.g_world = Vec3(0, 0, -cfg_.gravity_m_s2);
  } else {
    x.g_world = -up_body * cfg_.gravity_m_s2;
  }
  if (mean_g.norm() < 3.0 * cfg_.init_gyro_bias_sigma_rad_s) x.bg = mean_g;
  // The tilt is off by atan(a_h / g), a_h the mean horizontal acceleration: a steady horizontal push
  // leaves the spread small but lengthens the mean to sqrt(g^2 + a_h^2), so a_h = sqrt(|mean|^2 - g^2)
  // (a vertical push counts too: the bound is conservative); a varying one shows in the spread.
  const double g = cfg_.gravity_m_s2, scaled = norm * accel_scale;
  const double push = std::sqrt(std::abs(scaled * scaled - g * g));
  tilt_sigma_rad = std::clamp(std::atan2(std::max(rms, push), g), kMinTilt, kMaxTilt);
  using namespace sidx;
  P = initialCovariance();
  P.block<3, 3>(kBg, kBg) = Mat3::Identity() * cfg_.init_gyro_bias_sigma_rad_s * cfg_.init_gyro_bias_sigma_rad_s;
  // The rotation error is in the body frame: R^T diag(tilt, tilt, yaw) R (a small yaw floor keeps P
  // positive definite).
  const double var_tilt = tilt_sigma_rad * tilt_sigma_rad;
  P.block<3, 3>(kRot, kRot) = x.R_world_imu.transpose() * Vec3(var_tilt, var_tilt, 1e-8).asDiagonal() * x.R_world_imu;
  P.block<3, 3>(kBa, kBa) = Mat3::Identity() * cfg_.init_accel_bias_sigma_mps2 * cfg_.init_accel_bias_sigma_mps2;
  P.block<3, 3>(kPos, kPos) = Mat3::Identity() * 1e-6;  // the origin
  P.block<3, 3>(kVel, kVel) = Mat3::Identity() * cfg_.init_speed_sigma_mps * cfg_.init_speed_sigma_mps;
  return true;
}

std::string ImuInitializer::status() const {
  std::ostringstream os;
  os.precision(3);
  if (ready()) {
    os << "the last " << samples_.size() << " IMU samples give no gravity (their mean specific force is zero or not finite)";
    return os.str();
  }
  os << "collecting the first " << cfg_.init_samples << " IMU samples (" << windowSeconds(cfg_) << " s)";
  if (first_utime_ >= 0) os << ": " << toSeconds(samples_.back().utime - first_utime_) << " s so far";
  return os.str();
}

}  // namespace livo
