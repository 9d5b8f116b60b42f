// Initialisation from motion, for a rig that does not rest at start (ImuInitializer found no static
// window within imu.init_static_wait_s).
//
// Method: the ESIKF of the odometry itself, run from the first frame on a throwaway voxel map, with
// priors that say what is not known: the world is the first IMU frame (R = I, p = 0), the velocity
// is unknown (sigma init_motion_speed_sigma_mps), gravity is the mean specific force of the first
// samples scaled to g with a wide prior (the rig accelerates: init_motion_gravity_sigma_mps2 per
// axis), the gyro bias 0 (init_gyro_bias_sigma_rad_s), the accelerometer bias 0
// (init_accel_bias_sigma_mps2). Each frame is propagated, undistorted and registered to the
// throwaway map of the frames before (point-to-plane, as always), which makes velocity, gravity and
// the gyro bias observable within a few frames (p_k = p_0 + v_0 t + g t^2 / 2 + the double integral
// of the rotated specific force: the filter solves this least-squares problem recursively). Once
// at least init_motion_min_updates LiDAR updates were accepted and the velocity sigma is below
// init_motion_max_speed_sigma_mps and the gravity direction's below init_motion_max_tilt_sigma_deg,
// the state is handed over: the world is rotated so that gravity points along -z (gravity_align),
// and the odometry's real map starts with that frame's scan, undistorted with the converged motion.
// The accelerometer scale (g units or m/s^2) is taken from the magnitude class of the first
// samples' mean specific force (|a| < 4: g units).
#pragma once

#include "livo/estimation/imu.hpp"
#include "livo/estimation/lio_update.hpp"
#include "livo/estimation/state.hpp"
#include "livo/map/voxel_map.hpp"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace livo {

struct MotionInitConfig {
  double speed_sigma_mps = 2.0;       ///< imu.init_motion_speed_sigma_mps: prior sigma of the unknown velocity
  double gravity_sigma_mps2 = 2.0;    ///< imu.init_motion_gravity_sigma_mps2: prior sigma per axis of gravity
  int min_updates = 5;                ///< imu.init_motion_min_updates: accepted LiDAR updates before handover
  double max_speed_sigma_mps = 0.05;  ///< imu.init_motion_max_speed_sigma_mps: velocity sigma for handover
  double max_tilt_sigma_deg = 0.5;    ///< imu.init_motion_max_tilt_sigma_deg: gravity direction sigma for handover
  void load(const ConfigNode& imu);   ///< keys of the `imu` section
};

class MotionInitializer {
 public:
  /// `prepare` undistorts and downsamples a sweep along an IMU trace (the odometry's own step 1c).
  using PreparePoints = std::function<std::vector<BodyPoint>(const LidarScan&, const std::vector<ImuTracePoint>&)>;
  MotionInitializer(const ImuConfig& imu, MotionInitConfig cfg, VoxelMapConfig map, LioConfig lio, int min_matches,
                    PreparePoints prepare);

  /// Runs one frame (time order). Returns converged(): the caller may then takeOver() (or go on
  /// feeding frames, e.g. while a static window may still come).
  bool process(const Frame& frame);
  /// Enough LiDAR updates, velocity and gravity direction known well enough (see the file comment).
  bool converged() const;
  /// The converged state, rotated so that gravity points along -z (gravity_align), and its
  /// covariance; points() are the last frame's points (IMU frame at its time).
  void takeOver(NavState& x, StateCov& P);
  double accelScale() const { return accel_scale_; }
  std::vector<BodyPoint>& points() { return points_; }
  int updates() const { return updates_; }
  std::string describe() const;

 private:
  bool start(const Frame& frame);
  void alignToGravity();

  ImuConfig imu_;
  MotionInitConfig cfg_;
  LioConfig lio_;
  int min_matches_;
  PreparePoints prepare_;
  std::unique_ptr<VoxelMap> map_;
  std::unique_ptr<ImuPropagator> propagator_;
  NavState x_;
  StateCov P_ = StateCov::Identity();
  double accel_scale_ = 1.0;
  bool started_ = false, map_started_ = false;
  int updates_ = 0, frames_ = 0;
  std::vector<BodyPoint> points_;
};

}  // namespace livo
