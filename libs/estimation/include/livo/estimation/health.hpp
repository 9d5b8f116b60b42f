// The filter's own health, every frame (docs/algorithms.md section 12): consistency checks whose
// bounds follow from the configured noise, and the frame's state from them: initialising, ok,
// degraded (a check is outside its bound: the pose is kept and flagged) or lost (the checks fail
// persistently: the estimate is not trusted).
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/types.hpp"

#include <deque>
#include <string>

namespace livo {

struct HealthConfig {
  /// The LiDAR's correction of the IMU's prediction, (x_post [-] x_prop)^T (P_prop + F)^-1 (...),
  /// with F the LiDAR's own resolution on the pose (range noise on the position, beam noise on the
  /// rotation), is a chi-square of at most 6 degrees of freedom when the filter is consistent; above
  /// this bound (6 dof, 0.1 %) the frame is inconsistent.
  double correction_chi2_max = 22.46;
  /// The share of the points in map voxels holding a plane that match one must not fall below this
  /// fraction of its median over the consistent frames of the last 4 window_s: the scan does not fit
  /// the map where the map says it should. Relative, because the share a correct pose reaches depends
  /// on the map's maturity (0.89 or more on the shipped room scenes, 0.55 on the revisit street while
  /// its young map fills, 2026-12-07); a filter that lost the map drops to a fraction of it (0.27
  /// against 0.93 on the demo with an IMU fault).
  double min_match_share = 0.5;
  /// Window of the persistence rule: the frame is lost when at least half of the frames of the last
  /// window_s seconds (and 3 or more) are inconsistent; the state returns to ok after window_s s
  /// without an inconsistent frame.
  double window_s = 0.5;
  /// A speed no rig of this configuration reaches, m/s: above it the estimate is lost at once.
  double max_speed_mps = 80.0;
  /// Experimental, off by default: from `lost`, register the scan against the map around the last
  /// trusted pose carried on at its velocity and restart the filter there (at most once per
  /// window_s). On the demo with an IMU fault it registers in the symmetric room to poses 0.4-0.8 m
  /// off, the first update after the restart takes a velocity jump and the run diverges again
  /// (docs/algorithms.md section 12, 2026-12-07).
  bool recover = false;

  /// Reads the `health` section (optional; every key has a default).
  void load(const ConfigNode& health);
};

enum class HealthState { Initialising, Ok, Degraded, Lost };
/// "initialising", "ok", "degraded", "lost" (frames.csv's state column).
const char* healthName(HealthState s);

/// What one frame tells the monitor (from the LiDAR-inertial step and the frame's result).
struct HealthInputs {
  Utime utime = 0;
  bool initialized = false;   ///< the filter has started (the frame has a pose)
  bool update_ran = false;    ///< the LiDAR update ran against a map (not the map's first scan)
  int n_matched = 0;
  int n_covered = 0;          ///< points in map voxels holding a plane
  int min_matches = 20;       ///< lio.min_matches: fewer covered points say nothing about the fit
  double correction_chi2 = 0.0;
  double correction_m = 0.0;  ///< the position part of the LiDAR's correction, m
  /// The map's planes' own accuracy, sqrt(lidar.range_noise_m^2 + voxel_map.min_eigen_value), m: a
  /// correction below it is no evidence that the pose left the map (it stays a degraded frame).
  double plane_sigma_m = 0.05;
  bool lidar_failed = false;  ///< the LiDAR update failed where the map should have matched
  bool repeated_sweep = false;  ///< the sweep repeats the previous one point for point (a frozen LiDAR)
  bool visual_used = false;
  double speed_mps = 0.0;
};

struct FrameHealth {
  HealthState state = HealthState::Initialising;
  /// This frame failed a consistency check that counts towards `lost`: the match share, the speed, or
  /// the correction's chi-square with a correction larger than the planes' accuracy. (A chi-square
  /// out of bound with a smaller correction, an overconfident filter that is still on the map, makes
  /// the frame degraded only.)
  bool inconsistent = false;
  /// What put the frame out of ok: ';'-separated, no commas (a CSV field); empty when ok.
  std::string reason;
};

/// One per filter; assess() once per frame, in time order. After a lost span the frames that follow
/// are degraded ("not re-anchored"): the filter is consistent again, but nothing has tied its frame
/// back to the map before the span.
class HealthMonitor {
 public:
  explicit HealthMonitor(HealthConfig cfg = {}) : cfg_(cfg) {}
  FrameHealth assess(const HealthInputs& in);
  const HealthConfig& config() const { return cfg_; }
  /// The state of the last assessed frame is lost (with health.recover its scans stay out of the map).
  bool lost() const { return lost_; }
  /// The first inconsistent frame of the current lost span (-1 when not lost).
  Utime lostSince() const { return lost_ ? lost_since_ : -1; }
  /// The filter was restarted at a pose registered against the map the run built before the lost
  /// span (at `t`): the span is closed and the frame anchored again; the next frames start afresh.
  void recovered(Utime t);

 private:
  HealthConfig cfg_;
  std::deque<std::pair<Utime, bool>> window_;  ///< (frame time, inconsistent) of the last window_s
  std::deque<std::pair<Utime, double>> shares_;  ///< (frame time, match share) of the consistent frames
  /// The median match share of the consistent frames of the last 4 window_s (-1: fewer than 3).
  double referenceShare() const;
  bool lost_ = false;
  Utime last_inconsistent_ = -1;
  Utime lost_since_ = -1;
  std::pair<Utime, Utime> lost_span_{-1, -1};  ///< the last lost span (first, last inconsistent frame)
};

}  // namespace livo
