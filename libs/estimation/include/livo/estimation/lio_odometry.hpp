// The LiDAR-inertial part of the per-frame pipeline: initialise, propagate, undistort, downsample,
// iterated point-to-plane update, degeneracy metric, map insertion.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/timing.hpp"
#include "livo/estimation/imu.hpp"
#include "livo/estimation/lio_update.hpp"
#include "livo/map/hybrid_map.hpp"
#include "livo/map/voxel_map.hpp"

#include <memory>
#include <stdexcept>
#include <string>

namespace livo {

struct LioOdometryConfig {
  ImuConfig imu;
  LioConfig lio;
  VoxelMapConfig map;
  Pose T_imu_lidar = Pose::Identity();
  std::string lidar_model = "generic";  ///< lidar.model: avia | mid360 | spinning32 | generic
  int min_matches = 20;  ///< fewer matched points: the update is skipped and the frame flagged

  /// Reads the rig sections imu, lidar (T_imu_lidar required) and the lio / voxel_map sections.
  void load(const ConfigNode& root);
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
  /// Standalone: owns an unbounded LiDAR map (a global-mode HybridMap built from cfg.map).
  explicit LioOdometry(LioOdometryConfig cfg);
  /// Inserts into and matches against `map`'s LiDAR map (not owned; must outlive this object; cfg.map
  /// is not used, the map has its own configuration). Sliding and the memory cap are the map owner's
  /// business (HybridMap::update, e.g. by Pipeline).
  LioOdometry(LioOdometryConfig cfg, HybridMap& map);
  /// Without a map: the map lives elsewhere (the map server). Only the phases below may be used;
  /// process() and map() throw std::logic_error.
  struct RemoteMapTag {};
  LioOdometry(LioOdometryConfig cfg, RemoteMapTag);

  /// Processes one frame in time order: predict(), update() against the map's LiDAR map, insertion of
  /// worldPoints() into it. Frames before the IMU is initialised only feed it.
  LioFrameResult process(const Frame& frame);

  // The phases of process(), for an estimator whose map is remote (steps 1-3, then 4, then 5 by the
  // map's owner):
  /// Steps 1-3: initialisation, propagation to the frame time, undistortion and downsampling. Returns
  /// true when r.points wait for update() (r.state holds the prediction); false when there is
  /// nothing to estimate (IMU not initialised yet, frame inside the initialisation window).
  bool predict(const Frame& frame, LioFrameResult& r);
  /// Step 4: the iterated update against `planes` (skipped before the first insertion). Sets r.state,
  /// r.P, r.lio_ms (since predict()) and the match results.
  void update(LioFrameResult& r, const PlaneFinder& planes);
  /// World points with covariance at the current posterior (what step 5 inserts).
  std::vector<PointWithCov> worldPoints(const std::vector<BodyPoint>& pts) const;
  /// Records that the frame's points went into the map (enables update() from the next frame on).
  void markInserted(LioFrameResult& r);

  /// Replaces the posterior (after a later update at the same time stamp, e.g. the visual one).
  void setState(const NavState& x, const StateCov& P) {
    x_ = x;
    P_ = P;
  }
  const LioOdometryConfig& config() const { return cfg_; }
  /// The LiDAR voxel map (the local map in hybrid mode).
  const VoxelMap& map() const {
    if (map_ == nullptr) throw std::logic_error("LioOdometry::map: the map is remote");
    return map_->lidar().voxels();
  }
  const NavState& state() const { return x_; }
  const StateCov& covariance() const { return P_; }
  bool initialized() const { return init_.done(); }
  const std::string& initMessage() const { return init_message_; }

 private:
  std::vector<BodyPoint> preparePoints(const LidarScan& sweep, const std::vector<ImuTracePoint>& trace) const;

  LioOdometryConfig cfg_;
  ImuInitializer init_;
  std::unique_ptr<ImuPropagator> propagator_;
  std::unique_ptr<HybridMap> own_map_;  ///< standalone only
  HybridMap* map_;                      ///< own_map_, the external map or null (remote)
  NavState x_;
  StateCov P_ = initialCovariance();
  Utime last_imu_fed_ = -1;
  bool map_started_ = false;
  Stopwatch watch_;  ///< predict() to update()
  std::string init_message_;
};

}  // namespace livo
