// The LiDAR-inertial part of the per-frame pipeline (frame_pipeline.hpp): initialise, propagate,
// undistort, downsample, iterated point-to-plane update, degeneracy metric, the registered points.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/timing.hpp"
#include "livo/estimation/imu.hpp"
#include "livo/estimation/imu_init.hpp"
#include "livo/estimation/motion_init.hpp"
#include "livo/estimation/lio_update.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/map/voxel_map_config.hpp"

#include <memory>
#include <string>

namespace livo {

struct LioOdometryConfig {
  ImuConfig imu;
  MotionInitConfig motion_init;  ///< keys imu.init_motion_* (initialisation without a static window)
  LioConfig lio;
  VoxelMapConfig map;
  Pose T_imu_lidar = Pose::Identity();
  std::string lidar_model = "generic";  ///< lidar.model: avia | mid360 | spinning32 | generic
  int min_matches = 20;  ///< fewer matched points: the update is skipped and the frame flagged

  /// Reads the rig sections imu, lidar (T_imu_lidar required) and the lio / voxel_map sections.
  void load(const ConfigNode& root);
};

/// The whole filter state after a frame: what a restarted estimator needs to continue in the same world
/// frame (LioOdometry::filterState / resume).
struct FilterState {
  NavState state;
  StateCov P = StateCov::Zero();
  double accel_scale = 1.0;  ///< accelerometer units found at initialisation (ImuPropagator)
};

/// What one frame produced (LiDAR-inertial part).
struct LioFrameResult {
  Utime utime = 0;
  bool initialized = false;  ///< false while the IMU initialisation is collecting samples
  bool lio_ok = false;       ///< the LiDAR update ran with enough matches
  bool map_started = false;  ///< this frame created the first map content
  NavState state;            ///< posterior at the frame time
  StateCov P = StateCov::Zero();
  int n_raw_points = 0;
  int n_points = 0;          ///< downsampled points used
  int n_matched = 0;
  int iterations = 0;
  double sigma_min = 0.0;    ///< degeneracy metric of the matched normals
  double rms_residual_m = 0.0;
  double lio_ms = 0.0;       ///< propagation + undistortion + update
  double map_ms = 0.0;       ///< map insertion
  std::vector<BodyPoint> points;  ///< the frame's downsampled points (IMU frame at utime)
  std::vector<int> matched_index;    ///< points that matched a plane (indices into points) ...
  std::vector<Vec3> matched_normals; ///< ... and that plane's normal
};

class LioOdometry {
 public:
  /// The map is not held here: the per-frame pipeline (frame_pipeline.hpp) hands update() the planes
  /// to match and inserts worldPoints() into the map itself (map_access.hpp).
  explicit LioOdometry(LioOdometryConfig cfg);

  // The LiDAR-inertial phases of a frame, in this order:
  /// Step 1: initialisation (at rest: imu_init.hpp; else from motion: motion_init.hpp), propagation
  /// to the frame time, undistortion and downsampling. Returns true when r.points wait for update()
  /// (r.state holds the prediction); false when there is nothing to estimate (IMU not initialised
  /// yet, frame inside the initialisation window).
  bool predict(const Frame& frame, LioFrameResult& r);
  /// Step 3: the iterated update against `planes` (skipped before the first insertion). Sets r.state,
  /// r.P, r.lio_ms (since predict()) and the match results. `pool`: threads of the association.
  void update(LioFrameResult& r, const PlaneFinder& planes, WorkerPool* pool = nullptr);
  /// World points with covariance at the current posterior (what step 3 inserts into the map).
  std::vector<PointWithCov> worldPoints(const std::vector<BodyPoint>& pts) const;
  /// Records that the frame's points went into the map (enables update() from the next frame on).
  /// After a coarse start in geometry that constrains every direction, the first scan defines the map
  /// frame: the attitude's tilt uncertainty moves to gravity's direction in that frame
  /// (mapFrameFromFirstScan; r.P is updated).
  void markInserted(LioFrameResult& r);

  /// Starts from another estimator's last state instead of initialising (a restart in the middle of a
  /// run: the map already holds that estimator's scans). `imu`: the samples after prior.state.utime
  /// (time ordered) that the next predict() propagates through up to its frame's own samples, so the
  /// outage costs only the IMU's drift over it. Before the first frame only; returns false (and does
  /// nothing) once initialised.
  bool resume(const FilterState& prior, std::vector<ImuSample> imu, const std::string& source);
  /// The state after the last frame, with its covariance and the accelerometer units (after initialized()).
  FilterState filterState() const { return FilterState{x_, P_, propagator_ ? propagator_->accelScale() : 1.0}; }

  /// True once a scan went into the map (update() runs from then on).
  bool mapStarted() const { return map_started_; }
  /// Replaces the posterior (after a later update at the same time stamp, e.g. the visual one).
  void setState(const NavState& x, const StateCov& P) {
    x_ = x;
    P_ = P;
  }
  const LioOdometryConfig& config() const { return cfg_; }
  const NavState& state() const { return x_; }
  const StateCov& covariance() const { return P_; }
  bool initialized() const { return initialized_; }
  /// How the IMU was initialised (after initialized()), or what it waits for.
  const std::string& initMessage() const { return init_message_; }
  /// Before initialized(): what the initialisation waits for, with the numbers.
  std::string waitMessage() const;

 private:
  std::vector<BodyPoint> preparePoints(const LidarScan& sweep, const std::vector<ImuTracePoint>& trace) const;
  enum class InitStep { Waiting, AtRest, InMotion, Coarse };
  /// Feeds the frame to the static initialiser and the motion initialiser; sets x_, P_ and the
  /// propagator when one of them is done.
  InitStep initialise(const Frame& frame);
  enum class Rest { Confirmed, Moved, Unknown, Unconfirmable };
  /// Whether the LiDAR saw the rig at rest during the static window the IMU chose.
  Rest confirmRest(const Frame& frame);
  void initAtRest(const Frame& frame);
  /// The deadline passed (ImuConfig::deadlineSeconds()): start from ImuInitializer::coarseState().
  bool initCoarse(const Frame& frame);
  /// x_ / P_ through the samples of `samples` after x_'s time and before this frame's own samples
  /// begin (the frame's propagation keeps its trace for the undistortion).
  void propagateUpToFrame(const std::vector<ImuSample>& samples, const Frame& frame);

  LioOdometryConfig cfg_;
  ImuInitializer init_;
  std::unique_ptr<MotionInitializer> motion_;  ///< until initialised
  bool initialized_ = false;
  int rest_rejections_ = 0;  ///< static IMU windows the LiDAR saw moving
  std::unique_ptr<ImuPropagator> propagator_;
  std::vector<ImuSample> resume_imu_;  ///< resume(): samples to propagate through before the next frame's
  NavState x_;
  StateCov P_ = initialCovariance();
  Utime last_imu_fed_ = -1;
  void mapFrameFromFirstScan();
  bool map_started_ = false;
  bool free_gravity_ = false;  ///< a coarse start where the LiDAR constrains every direction
  Stopwatch watch_;  ///< predict() to update()
  std::string init_message_;
};

}  // namespace livo
