// The filter's start (docs/algorithms.md section 1, "Start"): one LiDAR-inertial start for every
// rig and every motion, no decision between rest and motion.
//
// The filter starts at the first frame that has imu.init_samples samples behind it, with the
// uncertainty the data leave:
//  - attitude: gravity's direction from the mean specific force of those samples, each rotated by the
//    gyro into the body frame at the start. The world frame is defined by that estimate (yaw by the
//    shortest rotation to +z), so the doubt is in gravity's direction in that frame, not in the
//    attitude: its horizontal sigma follows from what the mean cannot tell apart from gravity (white
//    noise over sqrt(n), the accelerometer bias prior, the variance beyond white noise -- motion,
//    vibration, aliased vibration -- and the horizontal acceleration that the specific force's norm
//    above g implies), at most imu.init_max_tilt_deg.
//  - velocity 0 with sigma imu.init_max_speed_mps / 2 per axis: an IMU cannot tell rest from constant
//    velocity, so the prior says what the rig can do, not what the IMU's calm suggests.
//  - biases 0 with their prior sigmas; the accelerometer's units (g or m/s^2) from the magnitude
//    of its mean.
// From then on every frame is propagated by the IMU and registered by the filter's own iterated
// point-to-plane update (lio_update.hpp), against a start map that only this class holds: the
// first scans, undistorted with the velocity known when they came. While the predicted position is
// uncertain by more than half a voxel, a correlative search over the start map's occupancy
// (occupancy_search.hpp; within 3 sigma of the prediction, at most the speed limit times the
// interval) gives the update its linearisation point, along the directions the map's planes
// constrain only. When the update moves the velocity, the sweep is undistorted again with the new
// one (up to 3 rounds). The start map is rebuilt from the current scan whenever that scan's smear
// (the velocity sigma times the sweep's duration) is well below the map's.
// The start is observed when a scan registered against a start map whose smear, like its own, is
// below a LiDAR return's range noise (or below three of them once it stops shrinking: a noisy IMU
// keeps that much velocity doubt between frames), in the directions the matched planes constrain: along a
// corridor's axis the LiDAR is no evidence of motion or rest, and there the velocity keeps the sigma
// the data gave it (the camera or later geometry may observe it). That frame's scan then seeds the
// odometry's map, and the frames before it have poses in state `initialising`.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/worker_pool.hpp"
#include "livo/estimation/imu.hpp"
#include "livo/estimation/lio_update.hpp"
#include "livo/estimation/state.hpp"
#include "livo/map/occupancy_search.hpp"
#include "livo/map/voxel_map.hpp"

#include <deque>
#include <memory>
#include <string>
#include <vector>

namespace livo {

struct StartConfig {
  double max_speed_mps = 15.0;   ///< imu.init_max_speed_mps: the fastest the rig moves at its start
  double max_tilt_deg = 30.0;    ///< imu.init_max_tilt_deg: cap of the start's gravity-direction sigma
  void load(const ConfigNode& imu);  ///< keys of the `imu` section
};

class FilterStart {
 public:
  /// Directions whose share of the matched normals' scatter, sqrt(lambda / N), is below this are
  /// not constrained by the planes (a single wall's along-wall directions: about 0.02).
  static constexpr double kConstrainedShare = 0.1;

  FilterStart(const ImuConfig& imu, StartConfig cfg, VoxelMapConfig map, LioConfig lio, int min_matches,
              const Pose& T_imu_lidar);

  /// Buffers the frame's IMU samples. With at least imu.init_samples of them (and samples in this
  /// frame): the prior at the frame's first sample, true. `describe()` then says what it holds.
  bool prior(const Frame& frame, NavState& x, StateCov& P, double& accel_scale);

  struct Step {
    bool registered = false;  ///< the update ran with enough matches
    bool observed = false;    ///< the start is observed: this frame's scan seeds the odometry's map
    int matched = 0, iterations = 0, rounds = 0;
    double rms_residual_m = 0.0;
    double sigma_min = 0.0;
    double smear_m = 0.0;     ///< this scan's smear sigma after the update (constrained directions)
    std::vector<int> matched_index;
    std::vector<Vec3> matched_normals;
  };
  /// One frame while starting. (x, P): the filter propagated through the frame (its `trace`) on entry,
  /// the posterior on return. `points`: the frame's prepared scan, re-prepared from `sweep` when the
  /// velocity changes (and the trace with it).
  Step update(NavState& x, StateCov& P, const LidarScan& sweep, std::vector<ImuTracePoint>& trace,
              std::vector<BodyPoint>& points, WorkerPool* pool);

  /// The start's prior, for the log (after prior()).
  const std::string& describe() const { return prior_message_; }
  /// What the start waits for, with the numbers.
  std::string status() const;
  int registeredFrames() const { return registered_; }
  int frames() const { return frames_; }

 private:
  /// Position search within `radius` of x's, along the start map's constrained directions.
  Vec3 searchPosition(const NavState& x, const std::vector<BodyPoint>& pts, double radius) const;
  /// Directions (columns) the start map's planes constrain.
  std::vector<Vec3> constrainedMapDirections() const;
  void insert(const std::vector<BodyPoint>& pts, const NavState& x, const StateCov& P);
  /// Largest velocity sigma along the directions the normals constrain, m/s.
  static double constrainedVelocitySigma(const StateCov& P, const std::vector<Vec3>& normals);

  ImuConfig imu_;
  StartConfig cfg_;
  VoxelMapConfig map_cfg_;
  LioConfig lio_;
  int min_matches_;
  Pose T_imu_lidar_;
  std::deque<ImuSample> samples_;  ///< before the start (bounded)
  std::unique_ptr<VoxelMap> map_;
  OccupancyPyramid occupancy_;
  double map_smear_m_ = 0.0;   ///< the worst smear sigma of the scans in the start map
  int registered_since_reseed_ = 0;
  int registered_ = 0, frames_ = 0;
  Utime start_utime_ = 0;
  std::string prior_message_;
  // The last frame's figures (status()).
  int last_matched_ = -1;
  double last_smear_m_ = -1.0, last_sigma_v_ = -1.0;
};

}  // namespace livo
