// The LiDAR-inertial part of the per-frame pipeline (frame_pipeline.hpp): initialise, propagate,
// undistort, downsample, iterated point-to-plane update, degeneracy metric, the registered points.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/modes.hpp"
#include "livo/estimation/esikf.hpp"
#include "livo/estimation/imu.hpp"
#include "livo/estimation/imu_init.hpp"
#include "livo/estimation/lio_update.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/map/voxel_map_config.hpp"
#include "livo/sensors/preprocess_config.hpp"

#include <bitset>
#include <string>

namespace livo {

struct LioOdometryConfig {
  ImuConfig imu;
  LioConfig lio;
  VoxelMapConfig map;
  Pose T_imu_lidar = Pose::Identity();
  LidarModel lidar_model = LidarModel::Generic;  ///< lidar.model (required)
  int min_matches = 20;  ///< fewer matched points: the update is skipped and the frame flagged

  /// Reads the rig sections imu, lidar (T_imu_lidar required) and the lio / voxel_map sections; the
  /// keys the preprocessing reads (imu.rate_hz) come from `pre`.
  void load(const ConfigNode& root, const PreprocessConfig& pre);
};

/// What one frame produced (LiDAR-inertial part).
struct LioFrameResult {
  Utime utime = 0;
  bool initialized = false;  ///< false while the IMU initialisation is collecting samples
  bool lio_ok = false;       ///< the LiDAR update ran with enough matches
  bool map_started = false;  ///< this frame created the first map content
  bool update_ran = false;   ///< the LiDAR update ran against the map (from the frame after its first scan)
  NavState state;            ///< the filter's state at the end of the step that wrote it (a record)
  StateCov P = StateCov::Zero();
  int n_raw_points = 0;
  int n_points = 0;          ///< downsampled points used
  int n_matched = 0;
  int iterations = 0;
  double sigma_min = 0.0;    ///< degeneracy metric of the matched normals
  double rms_residual_m = 0.0;
  int n_covered = 0;             ///< points in root voxels holding a plane (LioUpdateResult::covered)
  double nis = 0.0;              ///< LioUpdateResult::nis
  double correction_chi2 = 0.0;  ///< LioUpdateResult::correction_chi2
  double correction_m = 0.0;     ///< LioUpdateResult::correction_m
  double lio_ms = 0.0;       ///< propagation + undistortion (predict) + update, without the map's answer
  double map_ms = 0.0;       ///< map insertion
  std::vector<BodyPoint> points;  ///< the frame's downsampled points (IMU frame at utime)
  std::vector<int> matched_index;    ///< points that matched a plane (indices into points) ...
  std::vector<Vec3> matched_normals; ///< ... and that plane's normal
};

class LioOdometry {
 public:
  /// The map is not held here: the per-frame pipeline (frame_pipeline.hpp) hands update() the planes
  /// to match and inserts scanForMap() into the map itself (map_access.hpp). The state is not held
  /// here either: `filter` (the pipeline's) is started by the initialisation and acted on by predict()
  /// and update(); it must outlive this object.
  LioOdometry(LioOdometryConfig cfg, Esikf& filter);

  // The LiDAR-inertial phases of a frame, in this order:
  /// Step 1: the start (the filter from the first window of IMU samples: imu_init.hpp), propagation
  /// to the frame time, undistortion and downsampling. Returns true when r.points wait for update()
  /// (r.state holds the prediction); false when there is nothing to estimate (IMU not initialised
  /// yet, frame inside the initialisation window).
  bool predict(const Frame& frame, LioFrameResult& r);
  /// Step 3: the iterated update against `planes` (skipped before the first insertion). Sets r.state,
  /// r.P, r.lio_ms (predict's time plus its own) and the match results. `pool`: threads of the association.
  void update(LioFrameResult& r, const PlaneFinder& planes, WorkerPool* pool = nullptr);
  /// Step 3's insertion: the frame's points in the world with their covariance at the filter's
  /// posterior, for the map. From then on the map holds a scan (update() runs from the next frame on).
  /// The first scan defines the map frame: its points carry no pose covariance.
  std::vector<PointWithCov> scanForMap(LioFrameResult& r);

  /// Starts from another estimator's last state instead of initialising (a restart in the middle of a
  /// run: the map already holds that estimator's scans). `imu`: the samples after prior.state.utime
  /// (time ordered) that the next predict() propagates through up to its frame's own samples, so the
  /// outage costs only the IMU's drift over it. Before the first frame only; returns false (and does
  /// nothing) once initialised.
  bool resume(const FilterState& prior, std::vector<ImuSample> imu, const std::string& source);
  /// True once a scan went into the map (update() runs from then on).
  bool mapStarted() const { return map_started_; }
  /// The frame being processed belongs to the map's first whole scan: inserted, not registered.
  bool seedingMap() const { return seeding_; }
  const LioOdometryConfig& config() const { return cfg_; }
  bool initialized() const { return initialized_; }
  /// How the IMU was initialised (after initialized()), or what it waits for.
  const std::string& initMessage() const { return init_message_; }
  /// Before initialized(): what the initialisation waits for, with the numbers.
  std::string waitMessage() const;

 private:
  /// Feeds the frame's IMU samples to the start; starts the filter once they span one window.
  bool initialise(const Frame& frame);
  /// x_ / P_ through the samples of `samples` after x_'s time and before this frame's own samples
  /// begin (the frame's propagation keeps its trace for the undistortion).
  void propagateUpToFrame(const std::vector<ImuSample>& samples, const Frame& frame);
  /// r.state / r.P: the filter's, as this step leaves them.
  void recordState(LioFrameResult& r) const;

  LioOdometryConfig cfg_;
  Esikf& filter_;
  ImuInitializer init_;
  bool initialized_ = false;
  std::vector<ImuSample> resume_imu_;  ///< resume(): samples to propagate through before the next frame's
  Utime last_imu_fed_ = -1;
  bool map_started_ = false;
  /// The map's first whole scan is still being gathered: frames are inserted without an update
  /// (until a frame revisits the azimuth cells covered so far, at most 1 s).
  bool seeding_ = false;
  std::bitset<36> seed_cells_;
  Utime seed_start_ = 0;
  std::string init_message_;
};

}  // namespace livo
