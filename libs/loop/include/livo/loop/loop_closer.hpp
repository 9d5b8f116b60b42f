// Loop closure over an odometry: keyframes, place search, geometric verification and the pose graph
// composed in one object, fed one odometry pose (and, on keyframes, its registered scan) at a time. The
// livo-loop process and livo-run --loop adapt it; docs/algorithms.md section 11.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/types.hpp"
#include "livo/loop/keyframe_store.hpp"
#include "livo/loop/loop_verifier.hpp"
#include "livo/loop/map_frame.hpp"
#include "livo/loop/packed_points.hpp"
#include "livo/loop/place_database.hpp"
#include "livo/loop/pose_graph.hpp"

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace livo {

struct LoopConfig {
  KeyframeConfig keyframes;
  PlaceDescriptorConfig descriptor;
  PlaceSearchConfig search;
  LoopVerifyConfig verify;
  PoseGraphConfig graph;
  /// loop.keyframe_points_m: a keyframe keeps one point per cube of this edge, within the descriptor's
  /// range (what verification registers against), packed to 6 bytes a point (packed_points.hpp)
  double keyframe_points_m = 0.25;
  int verify_candidates = 3;        ///< loop.verify_candidates: best candidates checked until one is accepted
  /// loop.loop_spacing_m: after an accepted loop, keyframes within this much travel are stored but not
  /// searched (a revisit gives one loop every few keyframes, not one at each)
  double loop_spacing_m = 10.0;
  /// loop.solve_sigmas: an accepted loop that agrees with the current map frame within this many of its
  /// sigmas (loop_sigma_m, loop_sigma_deg) joins the graph without a solve (finish() solves what is left)
  double solve_sigmas = 3.0;
  /// loop.points_budget_mb: keyframe points kept in memory; older keyframes' points go to a spill file
  /// (read back when a candidate needs them); 0: no budget
  double points_budget_mb = 128.0;
  std::string spill_dir;  ///< loop.spill_dir: where the spill file goes ("": the system's temporary directory)
  // A saved site map (site_map.hpp) and localising in one (relocaliser.hpp).
  double site_tile_m = 100.0;      ///< loop.site_tile_m: edge of a site map's point tiles
  double site_budget_mb = 64.0;    ///< loop.site_budget_mb: tiles' points held while localising (0: all)
  int relocalise_every_frames = 5; ///< loop.relocalise_every_frames: before localised, try every Nth frame
  /// loop.prior_map_planes: once localised, the site map's keyframe points within the descriptor's range
  /// of the robot go into the odometry's LiDAR map (each keyframe once), so that the map's planes serve
  /// the LiDAR update (livo-run --prior-map); one keyframe per cell of keyframe_distance_m
  bool prior_map_planes = true;
  double relocalise_agree_m = 0.5;    ///< loop.relocalise_agree_m: two tries agree within this ...
  double relocalise_agree_deg = 2.0;  ///< loop.relocalise_agree_deg: ... and this, to localise
  /// loop.outside_map_after_m: no map keyframe verified over this much travel: outside the map
  /// (default 0: twice the descriptor's range)
  double outside_map_after_m = 0.0;

  /// Reads the `loop` section. The LiDAR's keys are read by their own sections' configs and handed in:
  /// lidar.max_range_m (bounds the descriptor), lidar.range_noise_m and lidar.beam_noise_deg (the
  /// verification's residual bound and point covariance).
  void load(const ConfigNode& loop, double lidar_max_range_m, double range_noise_m, double beam_noise_deg);
};

/// What one odometry pose did.
struct LoopStep {
  bool keyframe = false;
  int node = -1;        ///< the keyframe's index (graph node, database entry)
  int candidates = 0;   ///< places the search proposed
  int checked = 0;      ///< of them verified
  bool loop = false;    ///< a loop was accepted
  bool solved = false;  ///< and the graph solved (it disagreed with the map frame)
  int loop_with = -1;   ///< the keyframe it closed with
  LoopCheck check;      ///< the last verification's result
  PoseGraphReport graph;
  double search_ms = 0.0, verify_ms = 0.0, graph_ms = 0.0;  ///< time of the descriptor + search, checks, solve
};

/// What the loop closure did over a run (the loop_* counters of stats.json).
struct LoopTotals {
  int candidates = 0;  ///< places the searches proposed
  int solves = 0;      ///< graph solves, finish()'s included
  double ms = 0.0, search_ms = 0.0, verify_ms = 0.0, graph_ms = 0.0;  ///< time of add() + finish() and parts
};

class LoopCloser {
 public:
  explicit LoopCloser(LoopConfig cfg);
  /// Takes the next odometry pose (body in the odometry frame). On a keyframe, `scan` is called for the
  /// frame's registered points in the odometry frame; the place is searched, candidates verified and, on
  /// a loop, the graph solved.
  LoopStep add(Utime t, const Pose& T_odom_body, const std::function<std::vector<Vec3>()>& scan);
  /// Solves the graph when loops joined it since the last solve (at the end of a run); false otherwise.
  bool finish();
  /// The correction after the last add() / finish(): every keyframe when `all` (or after a solve), else
  /// the newest keyframe only; `final` marks the one sent at exit.
  MapCorrection correctionMessage(bool all, bool final = false) const;
  /// T_map_odom: the odometry frame in the map frame (identity until a loop is closed).
  const Pose& correction() const { return graph_.correction(); }
  const PoseGraph& graph() const { return graph_; }
  const PlaceDatabase& places() const { return places_; }
  const LoopCheckCounts& checks() const { return verifier_.counts(); }
  /// Keyframe i's thinned points in its keyframe frame (from memory or the spill file).
  PackedPoints keyframePoints(int i) const { return store_.get(i); }
  int loopsAccepted() const { return graph_.loops(); }
  /// Keyframe points held (in memory or spilled) and the bytes of those in memory and on disk.
  std::size_t pointsHeld() const { return points_held_; }
  std::size_t spilledBytes() const { return store_.spilledBytes(); }
  const LoopTotals& totals() const { return totals_; }
  /// The loop_* counters (stats.json) and the one-line summary of livo-run --loop and livo-loop.
  void addCounters(std::map<std::string, double>& c) const;
  std::string summary() const;

 private:
  LoopStep addKeyframe(Utime t, const Pose& T_odom_body, const std::function<std::vector<Vec3>()>& scan);

  LoopConfig cfg_;
  KeyframeSelector selector_;
  PlaceDatabase places_;
  LoopVerifier verifier_;
  PoseGraph graph_;
  KeyframeStore store_;  // per keyframe, its points in its keyframe frame, thinned
  std::size_t points_held_ = 0;
  double last_loop_path_m_ = -1e300;
  bool unsolved_loops_ = false;
  bool solved_last_ = false;  ///< the last add() / finish() solved the graph
  LoopTotals totals_;
  std::vector<std::pair<std::int32_t, std::int32_t>> loop_edges_;
};

}  // namespace livo
