// The per-frame pipeline on plain structs, shared by livo-run, the estimator process and the tests:
// sensor data in (IMU, LiDAR scans, images), frame results out.
//
// Per frame: (1) recut the LiDAR stream at the image time with the IMU samples covering the sweep
// (Recombiner), (2) propagate the IMU, undistort and run the iterated LiDAR update (LioOdometry),
// (3) degeneracy check of the matched plane normals, (4) map update.
#pragma once

#include "livo/common/config.hpp"
#include "livo/estimation/lio_odometry.hpp"
#include "livo/estimation/selector_config.hpp"
#include "livo/sensors/camera_config.hpp"
#include "livo/sensors/recombiner.hpp"

#include <functional>
#include <string>

namespace livo {

struct PipelineConfig {
  PreprocessConfig preprocess;
  LioOdometryConfig lio;
  CameraConfig camera;
  SelectorConfig selector;
  std::string visual_mode = "adaptive";  ///< adaptive | all | off (command line)
  std::string map_mode = "hybrid";       ///< hybrid | global (command line)

  /// Reads every section a rig config may hold that the pipeline uses (not channels).
  void load(const ConfigNode& root);
};

struct FrameResult {
  LioFrameResult lio;
  double total_ms = 0.0;
  bool degenerate = false;     ///< sigma_min below the threshold for degenerate_frames frames in a row
  bool visual_used = false;
  int n_visual_points = 0;
  double vio_ms = 0.0;
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
  const PipelineConfig& config() const { return cfg_; }
  std::size_t framesProcessed() const { return frames_; }

 private:
  FrameResult processFrame(const Frame& frame);

  PipelineConfig cfg_;
  Recombiner recombiner_;
  LioOdometry odometry_;
  int low_sigma_run_ = 0;  ///< consecutive frames with sigma_min below the threshold
  std::size_t frames_ = 0;
};

}  // namespace livo
