// The output directory of a run (livo-run --out DIR, livo-exporter --out DIR):
//   trajectory.tum  IMU pose in the world frame per frame (flushed per line)
//   frames.csv      one row per frame: t, lio_ms, vio_ms, total_ms, sigma_min, degenerate, visual_used,
//                   n_points, n_planes_matched, n_visual_points, map_bytes, n_longterm_points (flushed
//                   per row; map_bytes: the map's accounted bytes after the frame, 0 when unknown, e.g.
//                   livo-exporter; n_longterm_points: of n_visual_points, those that came through the
//                   long-term visual map, held by it or returned from it on a revisit),
//                   time_offset_s, time_offset_sigma_s (camera.estimate_time_offset: the camera's time
//                   offset estimate and its sigma; nan when not estimated), state (frameState below),
//                   reason (why the state is not ok: the failed checks with their values, ';'-separated)
//   stats.json      frames, visual_frames, degenerate_frames, timed_frames, timing_ms {lio, vio,
//                   vio_per_visual_frame, map, total} x {mean, median, p95, max}, peak_rss_mb, map
//                   camera {time_offset_estimate_s, time_offset_sigma_s} (the last frame's, when estimated),
//                   {local_voxels, visual_points_local, visual_points_longterm, bytes, and where the
//                   map is in the process (livo-run) its parts bytes_lidar, bytes_visual_local,
//                   bytes_visual_longterm, bytes_index}, plus
//                   run-specific counters. Timing statistics cover the frames after initialisation
//                   (timed_frames: those with a pose); vio_per_visual_frame only the frames that ran
//                   the visual update (vio averages over every timed frame, zeros included).
#pragma once

#include "livo/common/so3.hpp"
#include "livo/common/types.hpp"
#include "livo/estimation/health.hpp"
#include "livo/eval/tum.hpp"

#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace livo {

/// What one frame reports for the output files.
struct FrameRecord {
  Utime utime = 0;
  bool has_pose = false;  ///< false before initialisation: no trajectory line
  Pose T_world_imu = Pose::Identity();
  double lio_ms = 0, vio_ms = 0, map_ms = 0, total_ms = 0;
  double map_wait_ms = 0;  ///< waiting for the map server (frame_row.hpp: what each time covers)
  double sigma_min = 0;
  bool degenerate = false;
  bool visual_used = false;
  bool lidar_failed = false;  ///< the LiDAR update failed on a map that should have matched
  int n_points = 0;
  int n_planes_matched = 0;
  int n_visual_points = 0;
  int n_longterm_visual_points = 0;  ///< of n_visual_points, those that came through the long-term map
  /// camera.estimate_time_offset: the camera's time offset estimate and its sigma after the frame, s.
  bool has_time_offset = false;
  double time_offset_s = 0.0, time_offset_sigma_s = 0.0;
  /// Accounted bytes of every map structure after this frame; 0 = unknown (livo-exporter) or not
  /// initialised. livo-run: the map's O(1) estimate with a memory cap, else an exact count every few
  /// frames carried forward (processes/livo-run/main.cpp).
  std::uint64_t map_bytes = 0;
  /// The filter's health (estimator_stats_t.health) and why (frames.csv's state and reason columns;
  /// the reason is not kept past the row).
  HealthState health = HealthState::Ok;
  std::string health_reason;
};

/// The frame's state in frames.csv's `state` column, as RunHealth counts it: initialising (no pose yet),
/// ok, degraded (a consistency check of the filter is out of its bound, or the LiDAR update failed:
/// the pose is kept and flagged; the `reason` column says which), lost (the estimate is not trusted).
/// (Degenerate frames are their own column.)
const char* frameState(const FrameRecord& f);

/// What a run did over time (stats.json section "health"), from its frames in order: the delay from
/// the first frame to the first pose, the time spent initialising (frames without a pose before the
/// first), with the LiDAR update failing, on the IMU alone (LiDAR failed and no image used),
/// LiDAR-degenerate, degraded and lost (the frame's state), the frames in each state, the lost spans
/// (their count and the first one's start) and the longest gap between consecutive poses. A frame
/// counts for the interval since the previous frame.
struct RunHealth {
  void addFrame(const FrameRecord& f);
  bool anyPose() const { return first_pose_ >= 0; }
  /// Seconds from the first frame to the first pose (-1 without a pose).
  double firstPoseDelaySeconds() const;
  /// The JSON object written as "health" (without a trailing newline).
  std::string json() const;
  double initialising_s = 0, lidar_failed_s = 0, imu_only_s = 0, degenerate_s = 0, longest_gap_s = 0;
  double degraded_s = 0, lost_s = 0;
  std::size_t frames_ok = 0, frames_degraded = 0, frames_lost = 0;
  std::size_t lost_spans = 0;       ///< runs of consecutive lost frames
  double first_lost_t = -1;         ///< the first lost frame's time, s (-1: none)
  bool anyLost() const { return lost_spans > 0; }
  std::string no_pose_reason;  ///< set by the run when it ends without a pose

 private:
  Utime first_ = -1, prev_ = -1, first_pose_ = -1, last_pose_ = -1;
  bool prev_lost_ = false;
};

/// Map size at the end of a run.
struct MapSummary {
  std::uint64_t local_voxels = 0;
  std::uint64_t visual_points_local = 0;
  std::uint64_t visual_points_longterm = 0;
  std::uint64_t bytes = 0;
  /// The parts of `bytes` (HybridMapStats), written when has_parts (livo-exporter sees only the total).
  bool has_parts = false;
  std::uint64_t bytes_lidar = 0, bytes_visual_local = 0, bytes_visual_longterm = 0, bytes_index = 0;
};

class RunOutputs {
 public:
  /// Creates `dir` (and parents) and opens trajectory.tum and frames.csv; throws std::runtime_error
  /// naming the path on failure. With `append` (livo-exporter) existing files are continued, never
  /// truncated: a line cut short by a kill is removed, and frames at or before the files' last time
  /// are left out of both (counted: skippedFrames()); stats.json covers this writer's frames.
  explicit RunOutputs(const std::string& dir, bool append = false);

  void addFrame(const FrameRecord& f);
  /// Writes stats.json (atomically: temp file + rename). `counters` are extra integer counters
  /// (e.g. preprocessing drops), `notes` extra strings.
  void writeStats(const MapSummary& map, double peak_rss_mb,
                  const std::map<std::string, double>& counters = {},
                  const std::map<std::string, std::string>& notes = {}, const RunHealth* health = nullptr) const;

  std::size_t frames() const { return records_.size(); }
  std::size_t posesWritten() const { return tum_.count(); }
  /// Append mode: poses trajectory.tum held when opened, and frames left out since (not after its end).
  std::size_t previousPoses() const { return tum_.previousCount(); }
  std::size_t skippedFrames() const { return skipped_frames_; }
  double lastPoseTime() const { return tum_.lastTime(); }
  const std::string& dir() const { return dir_; }
  /// Human-readable summary (frames, timings) for stdout.
  std::string summary(double peak_rss_mb) const;

 private:
  std::string dir_;
  bool append_;
  TumWriter tum_;
  std::ofstream csv_;
  std::vector<FrameRecord> records_;
  /// Append mode: the last frame time in either file; frames must come after it.
  double after_t_ = -std::numeric_limits<double>::infinity();
  std::size_t skipped_frames_ = 0;
};

}  // namespace livo
