// Core of livo-exporter: turns the estimator's and the map server's messages into an output directory
// with the same files as livo-run (RunOutputs):
//   LIVO_ODOMETRY + LIVO_ESTIMATOR_STATS of one frame (same utime) -> a trajectory.tum line and a
//       frames.csv row, written and flushed as soon as both arrived (or when a later frame completes,
//       or on finish, with what arrived), so a killed exporter loses at most the frames in flight
//       (its map_bytes column stays 0: no per-frame map size reaches the exporter);
//   LIVO_REGISTERED_SCAN -> map.pcd (voxel grid, colour where a camera saw the point) and map.bt
//       (rays from the frame's odometry position), written by finish();
//   LIVO_MAP_STATS -> the newest one is the `map` section of stats.json, written by finish();
//   LIVO_MAP_CORRECTION (livo-loop) -> trajectory_map.tum, written by finish() when a correction came:
//       every posed frame in the loop-corrected map frame (MapFrameTrajectory, as livo-run --loop).
// Frames arriving at or before a frame already written are counted and dropped (the TUM file stays
// strictly increasing). Only message times are used. An existing trajectory.tum / frames.csv in the
// output directory is continued, never truncated (a restarted exporter: RunOutputs' append mode);
// map.pcd, map.bt and stats.json are written at finish() from what this process received.
#pragma once

#include "livo/io/channels.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/io/loop_messages.hpp"
#include "livo/io/map_messages.hpp"
#include "livo/io/run_outputs.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/map_export.hpp"

#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <string>

namespace livo {

class ExporterNode {
 public:
  /// Subscribes on `lcm` and creates `out_dir` with trajectory.tum and frames.csv (throws
  /// std::runtime_error naming the path when it cannot).
  ExporterNode(LcmNode& lcm, const ChannelConfig& channels, const MapExportConfig& cfg, const std::string& out_dir,
               std::ostream* log);

  // Message handlers (validated structs; also called directly by tests).
  void onOdometry(const OdometryOutput& o);
  void onStats(const EstimatorStats& s);
  void onRegisteredScan(const RegisteredScan& s);
  void onMapStats(const MapStats& m);
  void onMapCorrection(const MapCorrection& c);

  /// Writes the frames still pending, stats.json, map.pcd and map.bt. Call once, at the end.
  void finish();
  /// One line of progress (frames, map points, rejects).
  std::string progressLine() const;
  /// Multi-line summary for stdout at exit.
  std::string summary() const;

  const RunOutputs& outputs() const { return outputs_; }
  const MapCloud& mapCloud() const { return cloud_; }
  OccupancyMap& occupancy() { return occupancy_; }
  const std::map<std::string, double>& counters() const { return counters_; }

 private:
  struct Pending {
    std::optional<OdometryOutput> odom;
    std::optional<EstimatorStats> stats;
  };
  struct HeldScan {
    Utime utime = 0;
    std::vector<Eigen::Vector3f> points;
  };
  /// False (and counted) when `t` is at or before a frame already written.
  bool acceptFrameTime(Utime t, const char* what);
  /// Writes complete frames and every older incomplete one; keeps at most kMaxPending in flight.
  void flushFrames(bool all);
  void writeFrame(Utime t, const Pending& p);
  void insertHeldScans(bool all);
  std::optional<Eigen::Vector3d> originAt(Utime t, bool nearest) const;

  static constexpr std::size_t kMaxPending = 16;  ///< frames waiting for their second message
  static constexpr std::size_t kMaxOrigins = 512; ///< odometry positions kept for the scan rays

  LcmNode& lcm_;
  ChannelConfig channels_;
  MapExportConfig cfg_;
  std::ostream* log_;
  RunOutputs outputs_;
  RunHealth health_;  ///< stats.json "health", from the frames written
  MapCloud cloud_;
  OccupancyMap occupancy_;

  std::map<Utime, Pending> pending_;
  bool wrote_any_ = false;
  Utime last_written_ = 0;
  std::map<Utime, Eigen::Vector3d> origins_;  ///< odometry positions by frame time
  std::deque<HeldScan> held_scans_;           ///< registered scans waiting for their odometry
  std::optional<MapStats> map_stats_;
  MapFrameTrajectory map_frame_;                       ///< livo-loop's keyframes
  std::vector<std::pair<Utime, Pose>> odometry_poses_;  ///< posed frames written, for trajectory_map.tum
  bool map_corrections_ = false;
  std::map<std::string, double> counters_;
  bool finished_ = false;
};

}  // namespace livo
