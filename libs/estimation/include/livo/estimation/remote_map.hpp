// The map access of livo-estimator: the map server's HybridMap behind a MapClient
// (livo/map/map_protocol.hpp), for the per-frame pipeline (frame_pipeline.hpp).
//
//   step 2:  a query for the plane leaves of the root voxels the predicted scan touches (each
//            point's voxel and the one neighbour VoxelMap::findBestPlane would try), searched with
//            PlaneIndex (the voxel map's gates and score);
//   step 3b: the registered points are kept for the update message;
//   step 6:  a second query for every visual point in the visual voxels of the registered scan; the
//            visual step runs on a per-frame copy of them;
//   step 7:  one MapUpdate: the registered points with covariance and every visual point the frame
//            created, changed or removed (a point without observations removes the id).
// A query that gets no answer in time (MapClient::request false) does not stop the estimator: the
// LiDAR update uses the planes of the last answer it got (the previous frame's neighbourhood), a
// missing visual answer skips the visual update, and the frame reports link.map_timeout.
//
// Differences to the single process (InProcessMap): the planes the update sees are the map server's
// at the time of the query, so they lag by the updates still in flight (none in lock-step
// operation); the visual normals are refined against the planes before this frame's insertion;
// local and long-term visual points compete in one selection grid (the hybrid map keeps one winner
// per map and cell before merging by the same rule, winsCell in visual_map.hpp).
#pragma once

#include "livo/estimation/map_access.hpp"
#include "livo/estimation/pipeline_config.hpp"
#include "livo/map/map_protocol.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/dual_visual_map.hpp"

#include <cstdint>
#include <unordered_map>
#include <vector>

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

class RemoteMap final : public MapAccess {
 public:
  /// Uses the voxel sizes and camera extrinsics of `cfg`; `client` must outlive this object.
  RemoteMap(const PipelineConfig& cfg, MapClient& client);

  const PlaneFinder& planesFor(const Frame& frame, const LioFrameResult& lio) override;
  void insertScan(std::vector<PointWithCov> points) override;
  bool holdsAround(const LioFrameResult&, int) override { return !link_.map_timeout ? link_.submap_planes > 0 : true; }
  FrameVisualMap visualMap(const Frame& frame, const NavState& x, const std::vector<VoxelKey>* frustum_keys) override;
  MapFrameReport finishFrame(const Frame& frame, const NavState& x) override;

  std::size_t timeouts() const { return timeouts_; }
  /// Submaps whose voxel size differs from this estimator's voxel_map.voxel_size_m (a configuration
  /// mismatch between the processes: the queried keys do not match the server's voxels).
  std::size_t voxelSizeMismatches() const { return voxel_size_mismatches_; }

 private:
  /// What identifies a change of a visual point by the visual step.
  struct PointSignature {
    std::size_t n_obs = 0;
    Utime newest = 0;
    int reference = -1;
    int bad_updates = 0;
    bool converged = false;
    Vec3 normal = Vec3::Zero();
    Vec3 p_world = Vec3::Zero();
    explicit PointSignature(const VisualPoint& p);
    bool same(const VisualPoint& p) const;
  };
  MapQuery queryAt(const Frame& frame, const NavState& x) const;
  /// Sends `q` and waits for its answer, counted in link_.
  bool ask(MapQuery& q, Submap& out);
  /// The created and changed points of the visual step in full, removed ones without observations.
  void collectVisualChanges(std::vector<VisualPoint>& out) const;

  double voxel_size_m_, visual_voxel_size_m_;
  Pose T_imu_camera_;
  MapClient& client_;
  PlaneIndex planes_;  ///< the last answered LiDAR submap
  /// Per visual frame: the visual points the server sent, all in its local map (so local and
  /// long-term points compete in one selection grid).
  DualVisualMap cache_;
  std::unordered_map<std::int64_t, PointSignature> before_;  ///< the cached points as they came
  std::int64_t first_new_id_ = 0;
  bool visual_ran_ = false;  ///< this frame's visual step ran on cache_
  bool estimating_ = false;  ///< this frame reached step 2 (an update is due at its end)
  MapLinkReport link_;       ///< this frame's, from step 2 to its end
  std::vector<PointWithCov> registered_;
  std::int64_t request_id_ = 0;
  std::size_t timeouts_ = 0, voxel_size_mismatches_ = 0;
};

}  // namespace livo
