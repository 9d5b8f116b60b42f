// The per-frame pipeline on plain structs, shared by livo-run, the estimator process and the tests:
// sensor data in (IMU, LiDAR scans, images), frame results out.
//
// Per frame: (1) recut the LiDAR stream at the image time with the IMU samples covering the sweep
// (Recombiner), (2) propagate the IMU, undistort, run the iterated LiDAR update and insert the scan into
// the voxel map (LioOdometry), (3) degeneracy check of the matched plane normals, (4) frame selection,
// (5) on selected images the photometric update, (6) the visual map update and (7) map maintenance:
// slides of the hybrid map and its memory cap (HybridMap::update; nothing in global mode).
#pragma once

#include "livo/common/config.hpp"
#include "livo/estimation/lio_odometry.hpp"
#include "livo/estimation/frame_selector.hpp"
#include "livo/estimation/selector_config.hpp"
#include "livo/estimation/vio_update.hpp"
#include "livo/map/hybrid_map.hpp"
#include "livo/map/visual_map.hpp"
#include "livo/sensors/camera_model.hpp"
#include "livo/sensors/camera_config.hpp"
#include "livo/sensors/recombiner.hpp"

#include <functional>
#include <memory>
#include <string>

namespace livo {

struct PipelineConfig {
  PreprocessConfig preprocess;
  LioOdometryConfig lio;
  CameraConfig camera;
  SelectorConfig selector;
  VioConfig vio;
  VisualMapConfig visual_map;
  HybridMapConfig map;  ///< section `map`; its mode comes from map_mode
  std::string visual_mode = "adaptive";  ///< adaptive | all | off (command line)
  std::string map_mode = "hybrid";       ///< hybrid | global (command line; overrides map.mode)

  /// Reads every section a rig config may hold that the pipeline uses (not channels).
  void load(const ConfigNode& root);
};

struct FrameResult {
  LioFrameResult lio;
  double total_ms = 0.0;
  bool degenerate = false;     ///< sigma_min below the threshold for degenerate_frames frames in a row
  bool visual_used = false;
  int n_visual_points = 0;     ///< visual points used by the update
  int n_new_visual_points = 0; ///< created this frame
  double vio_rms_before = 0.0, vio_rms_after = 0.0;  ///< photometric RMS, gray levels
  double vio_ms = 0.0;
  MapUpdateReport map;         ///< step 7: slides, evictions, bytes (estimate unless recounted), ms
};

class Pipeline {
 public:
  using FrameCallback = std::function<void(const Frame&, const FrameResult&)>;
  explicit Pipeline(PipelineConfig cfg);

  void addImu(const ImuSample& s) { recombiner_.addImu(s); }
  void addScan(const LidarScan& s) { recombiner_.addScan(s); }
  /// Gray8 images (convert other formats first: livo/io/image_convert.hpp).
  void addImage(const Image& img) { recombiner_.addImage(img); }
  /// End of input: lets the recombiner emit what it still holds.
  void flush() { recombiner_.flush(); }
  /// Runs every frame that is complete; calls `cb` per frame in time order. Returns the count.
  std::size_t processReady(const FrameCallback& cb);

  const Recombiner& recombiner() const { return recombiner_; }
  const LioOdometry& odometry() const { return odometry_; }
  /// The camera model at the processing scale (null without a camera).
  const CameraModel* camera() const { return camera_.get(); }
  /// The local visual map (hybrid mode) or the only one (global mode).
  const VisualMap& visualMap() const { return map_->visual().local(); }
  /// The whole map: LiDAR map, local and long-term visual maps, counters.
  const HybridMap& map() const { return *map_; }
  /// Exact sizes and bytes of every map structure (walks them all: call at stats rate). For stats.json
  /// map {local_voxels, visual_points_local, visual_points_longterm, bytes}.
  HybridMapStats mapStats() const { return map_->stats(); }
  /// Frame images whose size does not match the camera calibration (never used by the visual update).
  std::size_t imagesWrongSize() const { return images_wrong_size_; }
  const PipelineConfig& config() const { return cfg_; }
  std::size_t framesProcessed() const { return frames_; }

 private:
  FrameResult processFrame(const Frame& frame);
  /// Steps 5-6 on `gray`, the frame's image at the processing scale.
  void visualStep(const Frame& frame, const Image& gray, FrameResult& r);

  PipelineConfig cfg_;
  Recombiner recombiner_;
  std::unique_ptr<HybridMap> map_;  ///< heap: odometry_ keeps a reference, the pipeline stays movable
  LioOdometry odometry_;
  std::unique_ptr<CameraModel> camera_;  ///< null without a camera
  FrameSelector selector_;
  std::size_t images_wrong_size_ = 0;
  std::size_t frames_ = 0;
};

}  // namespace livo
