// Initialisation from motion, for a rig that does not rest at start (ImuInitializer found no static
// window within imu.init_static_wait_s, or the LiDAR saw the "static" window move).
//
// Method (two steps, from the first frame on):
//  1. LiDAR odometry on a throwaway voxel map: each frame's rotation is predicted by integrating the
//     gyro (bias 0), its position by constant velocity from the last two fixes; the sweep is
//     undistorted along that motion and registered point-to-plane (the odometry's own iterated
//     update, with priors of init_motion_rot_sigma_deg on the rotation and init_motion_pos_sigma_m
//     on the position and nothing else free). The map is rebuilt once the second fix gives a
//     velocity, so that the first scan is undistorted too. The first two registrations do not trust
//     the prediction (nothing yet says how fast the rig moves; at 12 m/s and 5 Hz a frame is 2.4 m
//     and point-to-plane converges only within about a voxel): a correlative search over an occupancy
//     pyramid of the map (occupancy_search.hpp) finds the translation within init_motion_max_speed_mps
//     times the frame interval, the sweep is undistorted again with the velocity it implies, and the
//     registration starts from there.
//  2. Gravity and velocity by least squares over the IMU between the fixes: in the first IMU frame,
//     p_k = v_0 t_k + g t_k^2 / 2 + alpha_k, alpha_k the double integral of the gyro-rotated specific
//     force from the first fix (t_k measured from it); rows weighted by the fix sigma
//     (2 lidar.range_noise_m). |g| is then fixed to gravity_m_s2 and v_0 solved again.
// The result is taken once at least init_motion_min_updates fixes were registered, the residual RMS
// is within 3 fix sigmas, and the sigmas of the current velocity and of the gravity direction are
// below init_motion_max_speed_sigma_mps and init_motion_max_tilt_sigma_deg. The world is then
// rotated so that gravity points along -z (gravity_align); the gyro bias starts at 0 with the prior
// init_gyro_bias_sigma_rad_s, the accelerometer bias at 0 with init_accel_bias_sigma_mps2. The
// accelerometer scale (g units or m/s^2) is taken from the magnitude class of the first samples'
// mean specific force (|a| < 4: g units). The fixes also tell whether the rig was at rest during a
// static IMU window (atRestSince): an IMU alone cannot tell rest from constant velocity.
#pragma once

#include "livo/common/config.hpp"
#include "livo/estimation/imu.hpp"
#include "livo/estimation/lio_update.hpp"
#include "livo/estimation/state.hpp"
#include "livo/estimation/undistort.hpp"
#include "livo/estimation/scan_registration.hpp"
#include "livo/map/voxel_map.hpp"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace livo {

struct MotionInitConfig {
  double rot_sigma_deg = 2.0;         ///< imu.init_motion_rot_sigma_deg: registration prior on the gyro rotation
  double pos_sigma_m = 0.5;           ///< imu.init_motion_pos_sigma_m: registration prior on the predicted position
  int min_updates = 5;                ///< imu.init_motion_min_updates: registered fixes before the result is taken
  double max_speed_sigma_mps = 0.05;  ///< imu.init_motion_max_speed_sigma_mps
  double max_tilt_sigma_deg = 0.5;    ///< imu.init_motion_max_tilt_sigma_deg
  double max_window_s = 10.0;         ///< imu.init_motion_max_window_s: fixes and samples kept (oldest dropped)
  double max_speed_mps = 15.0;        ///< imu.init_motion_max_speed_mps: the first fixes' search radius per second
  void load(const ConfigNode& imu);   ///< keys of the `imu` section
};

class MotionInitializer {
 public:
  /// The first fixes' search, their velocity (velocityBody) and a coarse start's free gravity
  /// direction (lio_odometry.hpp) need every direction constrained: weakestShare() at least this
  /// (a single wall's along-wall direction has about 0.02; random rig 5's street with clutter 0.13).
  static constexpr double kConstrainedShare = 0.1;

  /// Sweeps are prepared as the odometry's step 1c (prepareScan, undistort.hpp) with `T_imu_lidar`.
  MotionInitializer(const ImuConfig& imu, MotionInitConfig cfg, VoxelMapConfig map, LioConfig lio, int min_matches,
                    const Pose& T_imu_lidar);

  /// Runs one frame (time order). Returns converged(): the caller may then takeOver() (or go on
  /// feeding frames, e.g. while a static window may still come).
  bool process(const Frame& frame);
  bool converged() const { return solved_; }
  /// The state at the last frame processed, world rotated to gravity (gravity_align), with its covariance.
  void takeOver(NavState& x, StateCov& P);
  /// Whether the LiDAR saw the rig at rest since `from`: the fixes since then stay within
  /// `tolerance_m` of each other along the directions the map constrains (constrainedProjector), or, when the fixes do not fit one motion (failed registrations, e.g.
  /// on a first map of planes one scan line wide), the scans since then match the first scan at its
  /// position at least half as well as at their fixes, counted over the fixes whose offset from that
  /// position the first scan's planes resolve. `known` is false with fewer than two fixes there.
  bool atRestSince(Utime from, double tolerance_m, bool& known) const;
  double accelScale() const { return accel_scale_; }
  int fixes() const { return static_cast<int>(fixes_.size()); }
  std::string describe() const;
  /// The weakest direction's share of the map planes' normal scatter (sqrt of the smallest
  /// eigenvalue over the trace, weighted by points): about 0 along a wall or a corridor's axis.
  double weakestShare() const;
  /// Projector onto the translation directions the map's planes constrain (eigen-directions of the
  /// point-weighted normal scatter with a share of at least kConstrainedShare); identity without planes.
  Mat3 constrainedProjector() const;
  /// Sum over the map's planes of N_j n_j n_j^T (N_j their point counts).
  Mat3 normalScatter() const;
  /// While not converged: fixes registered of those needed, and why the solution is not taken.
  std::string status() const;
  /// The velocity of the last two fixes in the IMU frame of the last one: the coarse start's velocity
  /// (lio_odometry.hpp). False with fewer than three fixes, or when the last two intervals' velocities
  /// disagree beyond what the motion and the fix noise allow, or when the map's planes leave a
  /// direction unconstrained (degenerate registrations slide).
  bool velocityBody(Vec3& v) const;

 private:
  struct Fix {
    Utime utime;
    Mat3 R;  ///< registered rotation (first IMU frame = world)
    Vec3 p;
    /// The scan's points (undistorted at rest) that find a plane of the first scan alone at the
    /// first scan's position (rotation R) and at p: the rest test's evidence when the fixes do not fit
    /// one motion (atRestSince). -1 when not counted.
    int matches_at_origin = -1, matches_at_fix = -1;
    /// RMS over the points matched at the origin of the fix's offset p projected on their planes'
    /// normals, m: how well the first scan tells the origin from the fix.
    double shift_on_normals_m = 0.0;
  };
  struct Solution {
    Vec3 v0 = Vec3::Zero(), g = Vec3::Zero();
    Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Identity();
    double rms = 0.0;
  };
  bool start(const Frame& frame);
  /// Gyro rotation, constant-velocity position trace over the frame's samples from the last fix.
  std::vector<ImuTracePoint> predictTrace(const Frame& frame, Mat3& R_pred, Vec3& p_pred) const;
  bool registerFrame(const Mat3& R_pred, const Vec3& p_pred, Mat3& R, Vec3& p) const;
  /// The first fixes: the correlative search's position for this frame (rotation R_pred), searched
  /// within max_speed_mps x the interval since the last fix around p_pred.
  Vec3 searchPosition(const Mat3& R_pred, const Vec3& p_pred, double dt) const;

  void insert(const std::vector<BodyPoint>& pts, const Mat3& R, const Vec3& p);
  /// Points of `pts` (IMU frame) that find a plane of first_map_ at pose (R, p), gated by their own
  /// noise and the planes' (no pose uncertainty).
  /// With `shift_rms_m`: the RMS over the matched points of `shift` projected on their planes' normals.
  int firstMapMatches(const std::vector<BodyPoint>& pts, const Mat3& R, const Vec3& p, const Vec3& shift = Vec3::Zero(),
                      double* shift_rms_m = nullptr) const;
  /// The fixes since `from` (at least two) fail to fit one motion, and the scans match the first scan at
  /// its position about as well as at their fixes: the registrations, not the rig, moved.
  bool fixesFailedAtRest(Utime from) const;
  /// Over the fixes since `from` whose offset from the first scan's position that scan resolves (the
  /// offset on the normals of the planes matched there above 3 fix sigmas): their count and their scans'
  /// matches against the first scan at its position and at the fixes.
  struct ResolvedMatches {
    int fixes = 0, at_origin = 0, at_fix = 0;
  };
  ResolvedMatches resolvedMatches(Utime from) const;
  /// The map from the first scan undistorted along v_cv_; `final`: the first scan is then dropped.
  void rebuildMap(bool final);
  /// The latest fix at least 50 ms before t (nullptr if none).
  const Fix* fixBefore(Utime t) const;
  /// Double integral alpha and single integral dv of the rotated specific force from the first fix.
  void integrate(Utime t, Mat3& R, Vec3& dv, Vec3& alpha) const;
  bool solve(Solution& s) const;
  bool accept(const Solution& s);  ///< records check_

  ImuConfig imu_;
  MotionInitConfig cfg_;
  LioConfig lio_;
  int min_matches_;
  Pose T_imu_lidar_;
  std::vector<BodyPoint> prepare(const LidarScan& sweep, const std::vector<ImuTracePoint>& trace) const {
    return prepareScan(sweep, trace, T_imu_lidar_, lio_);
  }
  std::unique_ptr<VoxelMap> map_;
  std::unique_ptr<VoxelMap> first_map_;  ///< the first scan alone, at rest (the rest test's reference)
  ScanRegistration registration_;  ///< the first fixes' search (no speed needed)
  SearchMap search_;               ///< of map_'s points while the first fixes are searched
  double accel_scale_ = 1.0;
  bool started_ = false, solved_ = false, rebuilt_ = false;
  Vec3 v_cv_ = Vec3::Zero();       ///< constant velocity of the last two fixes (world = first IMU frame)
  std::vector<ImuSample> samples_; ///< since the first fix
  std::vector<Fix> fixes_;
  LidarScan first_sweep_;          ///< re-undistorted when the map is rebuilt
  Frame first_frame_imu_;          ///< the first frame's IMU samples (for its trace)
  Solution solution_;
  std::vector<BodyPoint> points_;
  Utime last_utime_ = 0;
  /// The last acceptance test (status()): residual RMS, and the sigmas when the residual passed (else -1).
  struct Check {
    bool done = false;
    double rms = 0, sigma_v = -1, sigma_tilt_deg = -1;
  } check_;
};

}  // namespace livo
