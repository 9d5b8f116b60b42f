// Step 6 of the per-frame pipeline (frame_pipeline.hpp: photometric update, visual map update),
// written once for the two places a visual map can be: the in-process hybrid map (InProcessMap,
// livo-run) and the estimator's per-frame copy of the visual points the map server sent (RemoteMap,
// livo-estimator).
#pragma once

#include "livo/estimation/lio_odometry.hpp"
#include "livo/estimation/vio_update.hpp"
#include "livo/map/dual_visual_map.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/visual_map.hpp"
#include "livo/sensors/camera_config.hpp"
#include "livo/sensors/camera_model.hpp"

#include <vector>

namespace livo {

/// The visual map one frame's visual step works on: the points it retrieves, observes, removes and
/// adds (DualVisualMap: the hybrid map's two visual maps in process, or livo-estimator's per-frame copy
/// of the map server's points), and the LiDAR planes around the frame that refine the points' normals
/// and take the rays of a frame without a registered scan (may be null).
struct FrameVisualMap {
  DualVisualMap* visual = nullptr;
  const PlaneFinder* planes = nullptr;
};

/// New-point candidates without a registered scan (docs/algorithms.md 5.4, ray casting): for each free
/// cell of the selection grid, the ray through its centre is stepped from min_depth_m to
/// max_depth_m by half a LiDAR voxel; the first step near a LiDAR plane of `planes` gives the ray's
/// intersection with that plane, with the plane's normal.
std::vector<NewPointCandidate> raycastCandidates(const PlaneFinder& planes, const CameraModel& cam,
                                                 const Pose& T_world_camera, const ImageGrid& grid,
                                                 const std::vector<bool>& occupied, double step_m, double min_depth_m,
                                                 double max_depth_m);

/// World points of the frame's body points at state `x`.
std::vector<Vec3> scanInWorld(const NavState& x, const std::vector<BodyPoint>& points);

struct VisualStepResult {
  VioUpdateResult update;
  std::vector<VisualPoint*> points;  ///< the points in view that were used (valid until the map changes)
  int n_new_points = 0;
  std::size_t removed_bad = 0;
  /// Points used by the update that came through the long-term visual map: held by it, or returned from
  /// it to the local map on a revisit (VisualPoint::from_longterm; also known to a remote estimator).
  int n_longterm_used = 0;
};

/// Step 6 at the LiDAR posterior (x, P): retrieval of the points in view of the scan, the
/// photometric update (x, P become its posterior when a point was used), then at the posterior the
/// photometric error bookkeeping, new observations + refinement, removal of bad points and new
/// points from the plane-matched LiDAR points in free cells.
/// Without a registered scan (a frame whose LiDAR update failed): `no_scan` holds the visual voxels
/// of the camera frustum to retrieve from, and new points come from ray casting into the map's
/// planes (raycastCandidates) instead of from the scan.
struct NoScanRetrieval {
  std::vector<VoxelKey> frustum_keys;
  double ray_step_m = 0.25;
  double min_depth_m = 0.1;
  double max_depth_m = 30.0;
};
VisualStepResult runVisualStep(const FrameVisualMap& map, NavState& x, StateCov& P, const Image& gray, const CameraModel& cam,
                               const Pose& T_imu_camera, const VioConfig& vio, Utime t, const LioFrameResult& lio,
                               const NoScanRetrieval* no_scan = nullptr, WorkerPool* pool = nullptr,
                               const CaptureMotion& motion = {});

}  // namespace livo
