// The map as the per-frame pipeline (frame_pipeline.hpp) reaches it: the seam between the frame's
// steps, written once, and where the map lives.
//
// The map's calls take what they need of the frame and return what they did; none writes into the
// frame's result (the pipeline records step 7's report).
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

/// What the map did for one frame, handed back at its end (step 7).
struct MapFrameReport {
  MapUpdateReport update;  ///< in process: slides, evictions, bytes (estimate unless recounted), ms
  MapLinkReport link;      ///< through the map server: queries, answers, waits, the update message
};

class MapAccess {
 public:
  virtual ~MapAccess() = default;
  /// Step 2: the planes the iterated LiDAR update matches against, around the predicted scan
  /// (`lio.state` is the prediction, `lio.points` the frame's points).
  virtual const PlaneFinder& planesFor(const Frame& frame, const LioFrameResult& lio) = 0;
  /// Step 3b: the frame's points in the world frame at the LiDAR posterior, with covariance.
  virtual void insertScan(std::vector<PointWithCov> points) = 0;
  /// Whether the map should have matched the scan: planes for at least `min_points` of the predicted
  /// scan's points (after a failed LiDAR update: otherwise the scan is new territory, the map is
  /// empty or still young, and it seeds the map instead of being dropped). The map server's answer
  /// knows only its submap's plane count (any plane counts). True when unknown (no answer).
  virtual bool holdsAround(const LioFrameResult& lio, int min_points) = 0;
  /// Step 6: the visual map for the frame's image, around the registered scan at the LiDAR posterior
  /// `x`, or in the visual voxels `frustum_keys` when the LiDAR update failed (no registered scan);
  /// its `visual` is null when it cannot be had (no answer from the map server): no visual update.
  /// Valid until finishFrame.
  virtual FrameVisualMap visualMap(const Frame& frame, const NavState& x, const std::vector<VoxelKey>* frustum_keys) = 0;
  /// Step 7: the frame is done at its final state `x`: map maintenance or the map server's update.
  /// Returns what the map did and what reaching it cost since the frame's step 2.
  virtual MapFrameReport finishFrame(const Frame& frame, const NavState& x) = 0;
};

}  // namespace livo
