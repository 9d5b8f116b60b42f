// What one frame of the per-frame pipeline (frame_pipeline.hpp) produced.
#pragma once

#include "livo/estimation/health.hpp"
#include "livo/estimation/image_check.hpp"
#include "livo/estimation/lio_odometry.hpp"
#include "livo/map/hybrid_map.hpp"

#include <cstddef>

namespace livo {

/// What reaching the map cost this frame. Zeros for the in-process map; for the map server the
/// queries, their answers and the update message (RemoteMap).
struct MapLinkReport {
  bool map_timeout = false;      ///< a query of this frame got no answer
  int queries = 0;               ///< sent this frame (0, 1 or 2)
  int timeouts = 0;
  std::size_t query_keys = 0;    ///< root voxel keys of the LiDAR query
  std::size_t submap_planes = 0;
  std::size_t visual_keys = 0;
  std::size_t submap_visual_points = 0;
  double wait_ms = 0.0;          ///< time spent waiting for answers (not in lio_ms / vio_ms)
  std::size_t update_points = 0;
  std::size_t update_visual_points = 0;  ///< created, changed or removed
};

struct FrameResult {
  LioFrameResult lio;
  double total_ms = 0.0;
  bool degenerate = false;     ///< sigma_min below the threshold for degenerate_frames frames in a row
  bool visual_used = false;
  int n_visual_points = 0;     ///< visual points used by the update
  int n_new_visual_points = 0; ///< created this frame
  int n_longterm_visual_points = 0;  ///< of n_visual_points, those that came through the long-term map
  double vio_rms_before = 0.0, vio_rms_after = 0.0;  ///< photometric RMS, gray levels
  double vio_ms = 0.0;
  /// camera.estimate_time_offset: the camera's time offset after this frame (camera.time_offset_s +
  /// the state's t_d) and its sigma, s; reset_time_offset: t_d left 3 prior sigmas and was reset.
  bool has_time_offset = false;
  double time_offset_s = 0.0, time_offset_sigma_s = 0.0;
  bool reset_time_offset = false;
  ImageStatus image = ImageStatus::Ok;  ///< a failed image (image_check.hpp) is never used
  MapUpdateReport map;         ///< step 7 in process (MapFrameReport::update): slides, evictions, bytes, ms
  MapLinkReport link;          ///< steps 2, 6, 7 through the map server (MapFrameReport::link)

  /// The LiDAR update failed although a map to match existed (no returns, or fewer than
  /// lio.min_matches matches): the frame counts as degenerate, its scan stays out of the map, and the
  /// visual update (if the camera can) carries the estimate.
  bool lidar_failed = false;
  bool map_seeded = false;
  /// The frame's sweep repeats the previous one point for point (a frozen or replaying LiDAR driver):
  /// its points are not used (the frame counts as a LiDAR failure).
  bool repeated_sweep = false;
  /// health.recover and the filter was lost: the scan stayed out of the map.
  bool scan_withheld = false;
  FrameHealth health;  ///< the filter's consistency checks and the frame's state (health.hpp)  ///< the LiDAR update failed with nothing around in the map: the scan seeded it
  bool lidarFailed() const { return lidar_failed; }
};

}  // namespace livo
