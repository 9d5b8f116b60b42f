// The per-frame pipeline with the map in another process (livo-estimator; the map server owns the
// HybridMap). Same steps as Pipeline (pipeline.hpp), with the map reached through a MapClient:
//
//   1-3. predict the frame (IMU propagation, undistortion, downsampling) and ask for the plane leaves
//        of the root voxels the predicted scan touches (each point's voxel and the one neighbour
//        VoxelMap::findBestPlane would try), then the iterated LiDAR update against those planes
//        (PlaneIndex: the same gates and score as the voxel map), degeneracy, frame selection;
//   4-6. on a selected image, a second query for every visual point in the visual voxels of the
//        registered scan; the visual step runs on a per-frame copy of them (retrieval per grid cell,
//        photometric update, observations, refinement against the frame's planes, new points);
//   7.   one MapUpdate: the registered points with covariance and every visual point the frame
//        created, changed or removed.
// A query that gets no answer in time (MapClient::request false) does not stop the estimator: the
// LiDAR update uses the planes of the last answer it got (the previous frame's neighbourhood), a
// missing visual answer skips the visual update, and the frame reports map_timeout.
//
// Differences to the single process (Pipeline): the planes the update sees are the map server's at
// the time of the query, so they lag by the updates still in flight (none in lock-step operation);
// the visual normals are refined against the planes before this frame's insertion; local and
// long-term visual points compete in one selection grid (the hybrid map keeps one winner per map and
// cell before merging; the nearer wins in both).
#pragma once

#include "livo/estimation/frame_selector.hpp"
#include "livo/estimation/lio_odometry.hpp"
#include "livo/estimation/pipeline.hpp"
#include "livo/map/map_protocol.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/visual_map.hpp"
#include "livo/sensors/camera_model.hpp"

#include <cstdint>
#include <memory>

namespace livo {

/// The estimator's link to the map server.
class MapClient {
 public:
  virtual ~MapClient() = default;
  /// Sends `q` and waits for the Submap with the same request id. False when none arrived in time
  /// (`out` is then unspecified).
  virtual bool request(const MapQuery& q, Submap& out) = 0;
  /// Sends the frame's map changes (no answer).
  virtual void send(const MapUpdate& u) = 0;
};

struct RemoteFrameResult {
  FrameResult frame;             ///< as Pipeline reports it (frame.map stays empty: the server's)
  bool map_timeout = false;      ///< a query of this frame got no answer
  int queries = 0;               ///< sent this frame (0, 1 or 2)
  int timeouts = 0;
  std::size_t query_keys = 0;    ///< root voxel keys of the LiDAR query
  std::size_t submap_planes = 0;
  std::size_t visual_keys = 0;
  std::size_t submap_visual_points = 0;
  double wait_ms = 0.0;          ///< time spent waiting for answers
  std::size_t update_points = 0;
  std::size_t update_visual_points = 0;  ///< created, changed or removed
  std::vector<PointWithCov> registered;  ///< the frame's points in the world frame (sent in the update)
};

class RemoteEstimator {
 public:
  /// Same configuration as Pipeline (map_mode and the map section are the map server's business).
  explicit RemoteEstimator(PipelineConfig cfg);
  /// Processes one recombined frame (time order).
  RemoteFrameResult process(const Frame& frame, MapClient& client);

  const PipelineConfig& config() const { return cfg_; }
  const CameraModel* camera() const { return camera_.get(); }
  const LioOdometry& odometry() const { return lio_; }
  std::size_t framesProcessed() const { return frames_; }
  std::size_t timeouts() const { return timeouts_; }
  std::size_t imagesWrongSize() const { return images_wrong_size_; }
  /// Submaps whose voxel size differs from this estimator's voxel_map.voxel_size_m (a configuration
  /// mismatch between the processes: the queried keys do not match the server's voxels).
  std::size_t voxelSizeMismatches() const { return voxel_size_mismatches_; }

 private:
  bool query(MapQuery& q, Submap& out, RemoteFrameResult& r, MapClient& client);
  void visualStep(const Frame& frame, const Image& gray, RemoteFrameResult& r, MapClient& client, MapUpdate& update);

  PipelineConfig cfg_;
  LioOdometry lio_;
  FrameSelector selector_;
  std::unique_ptr<CameraModel> camera_;
  PlaneIndex planes_;  ///< the last answered LiDAR submap
  VisualMap cache_;    ///< per visual frame: the visual points the server sent
  std::int64_t request_id_ = 0;
  std::size_t frames_ = 0, timeouts_ = 0, images_wrong_size_ = 0, voxel_size_mismatches_ = 0;
};

}  // namespace livo
