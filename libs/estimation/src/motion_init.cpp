#include "livo/estimation/motion_init.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <sstream>

namespace livo {

void MotionInitConfig::load(const ConfigNode& n) {
  n.get("init_motion_speed_sigma_mps", speed_sigma_mps).get("init_motion_gravity_sigma_mps2", gravity_sigma_mps2);
  n.get("init_motion_min_updates", min_updates).get("init_motion_max_speed_sigma_mps", max_speed_sigma_mps);
  n.get("init_motion_max_tilt_sigma_deg", max_tilt_sigma_deg);
  n.check(speed_sigma_mps > 0 && speed_sigma_mps < 100, "init_motion_speed_sigma_mps", "must be in (0, 100) m/s");
  n.check(gravity_sigma_mps2 > 0 && gravity_sigma_mps2 < 20, "init_motion_gravity_sigma_mps2", "must be in (0, 20) m/s^2");
  n.check(min_updates >= 2 && min_updates <= 1000, "init_motion_min_updates", "must be in [2, 1000]");
  n.check(max_speed_sigma_mps > 0, "init_motion_max_speed_sigma_mps", "must be > 0");
  n.check(max_tilt_sigma_deg > 0 && max_tilt_sigma_deg < 30, "init_motion_max_tilt_sigma_deg", "must be in (0, 30) deg");
}

MotionInitializer::MotionInitializer(const ImuConfig& imu, MotionInitConfig cfg, VoxelMapConfig map, LioConfig lio,
                                     int min_matches, PreparePoints prepare)
    : imu_(imu), cfg_(cfg), lio_(lio), min_matches_(min_matches), prepare_(std::move(prepare)),
      map_(std::make_unique<VoxelMap>(map)) {}

bool MotionInitializer::start(const Frame& frame) {
  if (frame.imu.empty()) return false;
  Vec3 mean = Vec3::Zero();
  for (const auto& s : frame.imu) mean += s.accel;
  mean /= double(frame.imu.size());
  const double norm = mean.norm();
  if (!(norm > 1e-3) || !std::isfinite(norm)) return false;  // no usable specific force yet
  accel_scale_ = norm < 4.0 ? imu_.gravity_m_s2 : 1.0;  // g units or m/s^2
  propagator_ = std::make_unique<ImuPropagator>(imu_, accel_scale_);
  x_ = NavState();
  x_.utime = frame.imu.front().utime;
  x_.g_world = -mean.normalized() * imu_.gravity_m_s2;  // the first IMU frame is the world
  using namespace sidx;
  P_ = initialCovariance();
  P_.block<3, 3>(kRot, kRot) = Mat3::Identity() * 1e-8;  // the world's definition
  P_.block<3, 3>(kPos, kPos) = Mat3::Identity() * 1e-8;
  P_.block<3, 3>(kVel, kVel) = Mat3::Identity() * cfg_.speed_sigma_mps * cfg_.speed_sigma_mps;
  P_.block<3, 3>(kGrav, kGrav) = Mat3::Identity() * cfg_.gravity_sigma_mps2 * cfg_.gravity_sigma_mps2;
  P_.block<3, 3>(kBg, kBg) = Mat3::Identity() * imu_.init_gyro_bias_sigma_rad_s * imu_.init_gyro_bias_sigma_rad_s;
  P_.block<3, 3>(kBa, kBa) = Mat3::Identity() * imu_.init_accel_bias_sigma_mps2 * imu_.init_accel_bias_sigma_mps2;
  started_ = true;
  return true;
}

bool MotionInitializer::process(const Frame& frame) {
  if (!started_ && !start(frame)) return false;
  if (frame.utime <= x_.utime) return false;
  ++frames_;
  std::vector<ImuTracePoint> trace;
  propagator_->propagate(x_, P_, frame.imu, frame.utime, &trace);
  points_ = prepare_(frame.sweep, trace);
  if (points_.empty()) return false;
  if (map_started_) {
    NavState x = x_;
    StateCov P = P_;
    const LioUpdateResult u = lidarUpdate(x, P, points_, *map_, lio_);
    if (u.matched >= min_matches_) {
      x_ = x;
      P_ = P;
      ++updates_;
    }
  }
  // The throwaway map grows with the registered scans (never with an unregistered one after the first).
  if (!map_started_ || updates_ > 0) {
    std::vector<PointWithCov> world;
    world.reserve(points_.size());
    for (const auto& bp : points_) world.push_back({x_.R_world_imu * bp.p_imu + x_.p_world_imu, worldPointCovariance(x_, P_, bp)});
    map_->insert(world);
    map_started_ = true;
  }
  return converged();
}

void MotionInitializer::takeOver(NavState& x, StateCov& P) {
  alignToGravity();
  x = x_;
  P = P_;
  map_.reset();  // the throwaway map is not needed any more
}

bool MotionInitializer::converged() const {
  if (updates_ < cfg_.min_updates) return false;
  using namespace sidx;
  const double var_v = Eigen::SelfAdjointEigenSolver<Mat3>(P_.block<3, 3>(kVel, kVel)).eigenvalues().maxCoeff();
  // Direction error of g: its covariance across g, over |g|^2.
  const Vec3 gd = x_.g_world.normalized();
  const Mat3 across = Mat3::Identity() - gd * gd.transpose();
  const Mat3 Pg = across * P_.block<3, 3>(kGrav, kGrav) * across.transpose();
  const double var_tilt =
      Eigen::SelfAdjointEigenSolver<Mat3>(Pg).eigenvalues().maxCoeff() / x_.g_world.squaredNorm();
  const double max_tilt = cfg_.max_tilt_sigma_deg * M_PI / 180.0;
  return std::sqrt(var_v) < cfg_.max_speed_sigma_mps && std::sqrt(var_tilt) < max_tilt;
}

void MotionInitializer::alignToGravity() {
  if (!imu_.gravity_align) return;
  const Mat3 R = Quat::FromTwoVectors(x_.g_world.normalized(), Vec3(0, 0, -1)).toRotationMatrix();
  x_.R_world_imu = R * x_.R_world_imu;
  x_.p_world_imu = R * x_.p_world_imu;
  x_.v_world = R * x_.v_world;
  x_.g_world = R * x_.g_world;
  // The rotation error is in the body frame (unchanged); position, velocity and gravity rotate.
  using namespace sidx;
  StateCov J = StateCov::Identity();
  for (int b : {kPos, kVel, kGrav}) J.block<3, 3>(b, b) = R;
  P_ = J * P_ * J.transpose();
}

std::string MotionInitializer::describe() const {
  using namespace sidx;
  std::ostringstream os;
  os << "IMU initialised in motion after " << frames_ << " frames (" << updates_
     << " LiDAR updates on a throwaway map): speed " << x_.v_world.norm() << " m/s (sigma "
     << std::sqrt(P_.block<3, 3>(kVel, kVel).diagonal().maxCoeff()) << "), gravity " << x_.g_world.norm()
     << " m/s^2, gyro bias [" << x_.bg.transpose() << "] rad/s, accel scale " << accel_scale_;
  return os.str();
}

}  // namespace livo
