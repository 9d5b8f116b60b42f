// livo-run's composition of the per-frame pipeline with everything in one process: sensor data in
// (IMU, LiDAR scans, images), the Recombiner recuts the LiDAR stream at the image times (what
// livo-preprocess does in the suite), and each complete frame runs through FramePipeline
// (frame_pipeline.hpp: the frame's steps, written once) against the in-process HybridMap.
#pragma once

#include "livo/estimation/frame_pipeline.hpp"
#include "livo/estimation/in_process_map.hpp"
#include "livo/estimation/pipeline_config.hpp"
#include "livo/map/hybrid_map.hpp"
#include "livo/map/visual_map.hpp"
#include "livo/sensors/recombiner.hpp"

#include <functional>
#include <utility>
#include <memory>

namespace livo {

class Pipeline {
 public:
  using FrameCallback = std::function<void(const Frame&, const FrameResult&)>;
  /// Throws std::invalid_argument naming a bad thread count.
  explicit Pipeline(PipelineConfig cfg);

  void addImu(const ImuSample& s) { recombiner_.addImu(s); }
  void addScan(const LidarScan& s) { recombiner_.addScan(s); }
  /// Gray8 images (convert other formats first: livo/io/image_convert.hpp).
  void addImage(const Image& img) { recombiner_.addImage(img); }
  void addImage(Image&& img) { recombiner_.addImage(std::move(img)); }
  /// End of input: lets the recombiner emit what it still holds.
  void flush() { recombiner_.flush(); }
  /// Runs every frame that is complete; calls `cb` per frame in time order. Returns the count.
  std::size_t processReady(const FrameCallback& cb);

  const Recombiner& recombiner() const { return recombiner_; }
  const FramePipeline& frames() const { return frames_; }
  const LioOdometry& odometry() const { return frames_.odometry(); }
  /// The camera model at the processing scale (null without a camera).
  const CameraModel* camera() const { return frames_.camera(); }
  /// The whole map: LiDAR map, local and long-term visual maps, counters.
  const HybridMap& map() const { return *map_; }
  /// Points of a prior map (a site map's keyframes near the robot, in the odometry frame) into the LiDAR
  /// map, between frames: their planes serve the next frames' LiDAR updates.
  void insertPriorPoints(const std::vector<PointWithCov>& points);
  /// Exact sizes and bytes of every map structure (walks them all: call at stats rate). For stats.json
  /// map {local_voxels, visual_points_local, visual_points_longterm, bytes}.
  HybridMapStats mapStats() const { return map_->stats(); }
  const PipelineConfig& config() const { return frames_.config(); }

 private:
  Recombiner recombiner_;
  std::unique_ptr<HybridMap> map_;       ///< heap: access_ keeps a reference, the pipeline stays movable
  std::unique_ptr<InProcessMap> access_;
  FramePipeline frames_;
};

}  // namespace livo
