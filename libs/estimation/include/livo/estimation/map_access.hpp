// The map as the per-frame pipeline (frame_pipeline.hpp) reaches it: the seam between the frame's
// steps, written once, and where the map lives.
//
//   InProcessMap (in_process_map.hpp): the HybridMap in the same process (livo-run, the tests);
//   RemoteMap (remote_map.hpp): the map server's HybridMap behind a MapClient (livo-estimator).
//
// Per estimated frame the pipeline calls, in this order: planesFor (step 2), insertScan (step 3b,
// only with a registered scan: an unregistered one never goes into the map), visualMap (step 6,
// only when the frame's image is selected), then finishFrame (step 7) once per frame after the IMU
// is initialised (also for a frame inside the initialisation window, which skips steps 2-6).
#pragma once

#include "livo/common/types.hpp"
#include "livo/estimation/frame_result.hpp"
#include "livo/estimation/visual_step.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/point_cov.hpp"

#include <vector>

namespace livo {

class MapAccess {
 public:
  virtual ~MapAccess() = default;
  /// Step 2: the planes the iterated LiDAR update matches against, around the predicted scan
  /// (r.lio.state is the prediction, r.lio.points the frame's points). Records its cost in r.link.
  virtual const PlaneFinder& planesFor(const Frame& frame, FrameResult& r) = 0;
  /// Step 3b: the frame's points in the world frame at the LiDAR posterior, with covariance.
  virtual void insertScan(std::vector<PointWithCov> points, FrameResult& r) = 0;
  /// Whether the map should have matched the scan: planes for at least `min_points` of the predicted
  /// scan's points (after a failed LiDAR update: otherwise the scan is new territory, the map is
  /// empty or still young, and it seeds the map instead of being dropped). The map server's answer
  /// knows only its submap's plane count (any plane counts). True when unknown (no answer).
  virtual bool holdsAround(const FrameResult& r, int min_points) = 0;
  /// Step 6: the visual map for the frame's image, around the registered scan at the LiDAR posterior
  /// (r.lio.state), or in the visual voxels `frustum_keys` when the LiDAR update failed (no
  /// registered scan); null when it cannot be had (no answer from the map server): no visual update.
  /// Valid until finishFrame.
  virtual VisualMapOps* visualMap(const Frame& frame, FrameResult& r, const std::vector<VoxelKey>* frustum_keys) = 0;
  /// Step 7: the frame is done (r.lio.state is final): map maintenance or the map server's update.
  virtual void finishFrame(const Frame& frame, FrameResult& r) = 0;
};

}  // namespace livo
