// The per-frame pipeline, written once for every place the map can be (map_access.hpp): livo-run and
// the tests with the map in process (InProcessMap), livo-estimator with the map server (RemoteMap).
//
// Per recombined frame (sweep recut at the image time + the IMU samples covering it + the image):
//   1. initialise from the IMU, propagate to the frame time, undistort and downsample the sweep;
//   2. the planes around the predicted scan (map access);
//   3. the iterated point-to-plane LiDAR update; the registered points go into the map;
//   4. degeneracy of the matched plane normals (sigma_min, several frames in a row); a frame whose
//      LiDAR update failed counts as degenerate (and its scan does not go into the map);
//   5. frame selection (adaptive: every image of an unproven start, then keyframes unless degenerate;
//      all; off);
//   6. on a selected image: the photometric update and the visual map's changes;
//   7. the frame's end at its final state (map maintenance, or the update message to the map server).
// Every decision of the frame (the image check, the degeneracy rule, the selector, when the visual
// step runs) is taken here and nowhere else. The filter's state has one owner, the pipeline's Esikf
// (esikf.hpp): steps 1 and 3 act on it through LioOdometry, step 6 in place; the frame's result
// records it at step 7.
#pragma once

#include "livo/common/worker_pool.hpp"
#include "livo/estimation/frame_result.hpp"
#include "livo/estimation/frame_selector.hpp"
#include "livo/estimation/image_check.hpp"
#include "livo/estimation/vignetting.hpp"
#include "livo/estimation/lio_odometry.hpp"
#include "livo/estimation/map_access.hpp"
#include "livo/estimation/pipeline_config.hpp"
#include "livo/sensors/camera_model.hpp"

#include <cstddef>
#include <memory>
#include <deque>

namespace livo {

class FramePipeline {
 public:
  /// Throws std::invalid_argument naming a bad thread count.
  explicit FramePipeline(PipelineConfig cfg);

  /// Runs steps 1-7 on one frame (time order) against `map`.
  FrameResult process(const Frame& frame, MapAccess& map);

  /// Continues another estimator's run from its last state (LioOdometry::resume; the covariance holds
  /// t_d's prior already). Before the first frame only: false once initialised.
  bool resume(const FilterState& prior, std::vector<ImuSample> imu, const std::string& source) {
    return lio_.resume(prior, std::move(imu), source);
  }

  const PipelineConfig& config() const { return cfg_; }
  /// The camera model at the processing scale (null without a camera).
  const CameraModel* camera() const { return camera_.get(); }
  const LioOdometry& odometry() const { return lio_; }
  /// The filter's state after the last frame (its snapshot() is what a restarted estimator resumes from).
  const Esikf& filter() const { return filter_; }
  /// Frame images whose size does not match the camera calibration (never used by the visual update).
  std::size_t imagesWrongSize() const { return image_counters_.wrong_size; }
  /// Camera failures per kind (image_check.hpp): images never used by the visual update.
  const ImageCheckCounters& imageCounters() const { return image_counters_; }
  /// camera.estimate_time_offset: times t_d left 3 prior sigmas and was reset to the prior.
  std::size_t timeOffsetResets() const { return time_offset_resets_; }
  /// Lost spans the filter recovered from (restarted at a pose registered against the map).
  std::size_t recoveries() const { return recoveries_; }

 private:
  /// The frame's image at the processing scale in `scratch` or the frame itself; null without a
  /// camera or an image, or when the image failed a check (image_check.hpp; counted in r.image).
  const Image* frameImage(const Frame& frame, Image& scratch, FrameResult& r);
  /// Step 3: LiDAR update against `planes`, then the registered points into the map.
  void lidarStep(MapAccess& map, const PlaneFinder& planes, FrameResult& r);
  /// Step 6 on `gray`, the frame's image at the processing scale (`lidar_failed`: retrieval from the
  /// camera frustum instead of the scan).
  void visualStep(const Frame& frame, const Image& gray, MapAccess& map, FrameResult& r, bool lidar_failed);
  /// Step 8: the health checks on the frame (health.hpp), and from `lost` the recovery: the frame's
  /// scan registered against the map around the last trusted pose carried on at its velocity, and
  /// on success the filter restarted there (docs/algorithms.md section 12).
  void healthStep(const Frame& frame, MapAccess& map, FrameResult& r);
  bool recover(const Frame& frame, MapAccess& map, FrameResult& r);
  /// What the health checks read of the frame's result.
  HealthInputs healthInputs(const FrameResult& r) const;
  /// The sweep repeats the previous frame's point for point (remembers this one's fingerprint).
  bool repeatsLastSweep(const LidarScan& sweep);
  std::uint64_t last_sweep_hash_ = 0;
  std::size_t last_sweep_size_ = 0;

  /// The filter after the frames whose state was ok, the last 2 s of them (a recovery starts from
  /// the last one at least health.window_s before the lost span's first inconsistent frame: the
  /// frames just before it may carry the fault already).
  struct Trusted {
    NavState x;
    StateCov P = StateCov::Zero();
  };
  std::deque<Trusted> trusted_;
  Utime last_recovery_try_ = -1;

  PipelineConfig cfg_;
  Esikf filter_;  ///< the one filter state; lio_ and visualStep act on it
  LioOdometry lio_;
  FrameSelector selector_;
  std::unique_ptr<CameraModel> camera_;  ///< null without a camera
  std::unique_ptr<WorkerPool> pool_;     ///< null with one thread
  ImageCheck image_check_;
  HealthMonitor health_;
  VignettingCorrection vignetting_;  ///< camera.vignetting (inactive at 0)
  ImageCheckCounters image_counters_;
  std::size_t time_offset_resets_ = 0;
  std::size_t recoveries_ = 0;
};

}  // namespace livo
