// Everything the viewer shows, updated from inbox batches and drawn by processes/livo-viewer: the
// accumulated map, the current scan, the trajectory, the latest figures for the overlay and the
// colours of each drawn point. Points above the highest pose plus `clip_above_m` are not drawn (a
// room's ceiling would hide the room from above; the map keeps them).
#pragma once

#include "livo/viewer/colour.hpp"
#include "livo/viewer/geometry.hpp"
#include "livo/viewer/inbox.hpp"
#include "livo/viewer/map_accumulator.hpp"
#include "livo/viewer/trajectory_track.hpp"

#include <deque>
#include <optional>
#include <string>
#include <vector>

namespace livo::viewer {

struct SceneConfig {
  MapAccumulatorConfig map;
  std::size_t max_poses = 200'000;
  double clip_above_m = 1.0;  ///< not drawn: points above the highest pose + this, m; <= 0: no clipping
  bool have_intensity = true;  ///< false for a run directory (map.pcd holds colours only)
};

/// Points with their colours, ready to draw.
struct ColouredPoints {
  std::vector<Eigen::Vector3f> xyz;
  std::vector<Rgb> rgb;
};

/// The figures of the text overlay.
struct OverlayData {
  std::string source;                      ///< "live udpm://..." or "run DIR"
  std::uint64_t frames = 0;                ///< poses received
  double rate_hz = 0.0;                    ///< frames per second of message time (last 2 s)
  double t_s = 0.0;                        ///< message time since the first pose, s
  std::optional<FrameStatsInput> frame;    ///< the latest per-frame figures
  std::optional<MapStatsInput> map;        ///< the latest map server figures
  std::size_t map_points = 0, scan_points = 0;
  double voxel_m = 0.0;
  std::uint64_t map_evicted = 0;
  DropCounters drops;
  std::size_t keyframes = 0, loops = 0;     ///< the loop closure's map frame (0: no livo-loop heard)
  std::size_t corrections_refused = 0;
  ViewMode view = ViewMode::kFollow;
  ColourMode colour = ColourMode::kHeight;
};

/// The overlay's lines (figures missing so far are left out).
std::string overlayText(const OverlayData& d);

class Scene {
 public:
  explicit Scene(const SceneConfig& cfg);

  /// Scans into the map (the last one becomes the current scan), poses into the trajectory, the
  /// latest statistics kept.
  void apply(InboxBatch batch);
  /// Points into the map only (a run directory's map.pcd: no current scan).
  void addMapPoints(const ScanInput& points);
  /// Forgets the map, the scan, the trajectory and the statistics (drop counters stay).
  void clear();

  const MapAccumulator& map() const { return map_; }
  const TrajectoryTrack& track() const { return track_; }
  const ScanInput& currentScan() const { return scan_; }
  std::uint64_t scanVersion() const { return scan_version_; }
  const std::optional<FrameStatsInput>& frameStats() const { return frame_; }
  const std::optional<MapStatsInput>& mapStats() const { return map_stats_; }
  const DropCounters& drops() const { return drops_; }
  /// Message time of the first and of the latest pose (nullopt before any).
  std::optional<Utime> firstUtime() const { return first_utime_; }
  std::optional<Utime> lastUtime() const;
  /// Seconds of message time since the first pose (0 before any).
  double elapsedS() const;
  /// Frames per second of message time over the last 2 s of poses.
  double rateHz() const;

  /// Points higher than this are not drawn (+inf without clipping or before any pose).
  double clipZ() const;
  /// The map's points below clipZ() in `mode`'s colours (height: 1st..99th percentile of the drawn
  /// heights; intensity: 0..99th percentile).
  ColouredPoints mapPoints(ColourMode mode) const;
  /// The current scan below clipZ(), in kScanColour.
  ColouredPoints scanPoints() const;

  /// The loop closure's map frame: the keyframes' map-frame positions in graph order (the corrected
  /// path) and the loop edges between known keyframes; version() changes with every correction.
  std::vector<Vec3> mapFramePath() const;
  std::vector<std::pair<Vec3, Vec3>> loopEdges() const;
  std::uint64_t mapFrameVersion() const { return map_frame_version_; }

  OverlayData overlay(const std::string& source, ViewMode view, ColourMode colour) const;
  const SceneConfig& config() const { return cfg_; }

 private:
  SceneConfig cfg_;
  MapAccumulator map_;
  TrajectoryTrack track_;
  ScanInput scan_;
  std::uint64_t scan_version_ = 0;
  std::optional<FrameStatsInput> frame_;
  std::optional<MapStatsInput> map_stats_;
  DropCounters drops_;
  std::optional<Utime> first_utime_;
  std::deque<Utime> recent_;  ///< pose times of the last 2 s
  MapFrameTrajectory map_frame_;
  std::uint64_t map_frame_version_ = 0;
  std::size_t corrections_refused_ = 0;
};

}  // namespace livo::viewer
