// Localising in a saved site map (site_map.hpp) with no initial pose: the odometry runs in its own
// frame; the relocaliser finds where that frame sits in the map's. Until it knows, it tries the current
// scan every few frames against the whole map (place search, then the geometric check of loop closure
// without the odometry's bound; a try where candidates verify at different places is ambiguous and
// counts for nothing); two tries at different times whose odometry-to-map transforms agree localise it. From then on every keyframe is checked against the map keyframes the current transform
// predicts (the odometry's drift bound since the last match applies), and each match is fused into the
// transform (weights from the odometry's drift since the last anchor, loop.odometry_sigma_*, against the
// match's, loop.loop_sigma_*; a match beyond 3 sigma is refused). Without a match for loop.outside_map_after_m of travel it reports that the robot left the
// map (the odometry goes on; frames stay carried by the last anchor) and says when it is back.
// docs/algorithms.md section 11, "Relocalisation".
#pragma once

#include "livo/loop/loop_closer.hpp"
#include "livo/loop/map_frame.hpp"
#include "livo/loop/site_map.hpp"

#include <functional>
#include <string>
#include <vector>

namespace livo {

struct RelocaliseStep {
  bool localised_now = false; ///< this frame localised for the first time
  bool back_in_map = false;   ///< this frame matched the map again after left_map
  bool matched = false;       ///< a map keyframe was verified (an anchor)
  bool left_map = false;      ///< this frame crossed loop.outside_map_after_m without a match
  int map_keyframe = -1;      ///< the matched map keyframe
  int candidates = 0, checked = 0;
  double ms = 0.0;
};

class Relocaliser {
 public:
  Relocaliser(const LoopConfig& cfg, SiteMap& map);
  /// Takes the next odometry pose; `scan` is called for the frame's registered points (odometry frame)
  /// when the frame is tried against the map.
  RelocaliseStep add(Utime t, const Pose& T_odom_body, const std::function<std::vector<Vec3>()>& scan);

  bool localised() const { return localised_; }
  /// T_map_odom of the last anchor (identity before the first).
  const Pose& correction() const { return T_map_odom_; }
  /// The anchors as map-frame keyframes (all, or the newest only): feed to MapFrameTrajectory for the
  /// frames' map poses.
  MapCorrection anchors(bool all = true) const;
  Utime firstLocalised() const { return first_localised_; }
  const LoopCheckCounts& checks() const { return verifier_.counts(); }
  int matches() const { return int(anchors_.size()); }
  /// "localised at t ... (x s after the first frame), N anchors, ..."
  std::string summary() const;
  void addCounters(std::map<std::string, double>& c) const;

 private:
  /// The map keyframes verified against the scan at K; the accepted one's T_map_odom in `H`.
  bool check(const Pose& K, const std::vector<Vec3>& local, bool bounded, RelocaliseStep& st, Pose& H);
  /// Fuses a match (T_map_odom `H`) at keyframe frame K into the current transform; false when it is
  /// farther from the prediction than 3 sigma (refused, counted).
  bool fuse(const Pose& K, const Pose& H);
  /// Two odometry-to-map transforms within loop.relocalise_agree_m and loop.relocalise_agree_deg.
  bool agree(const Pose& a, const Pose& b) const;

  LoopConfig cfg_;
  SiteMap& map_;
  KeyframeSelector selector_;
  PlaceDatabase places_;
  LoopVerifier verifier_;
  bool localised_ = false, outside_ = false, have_hypothesis_ = false;
  Pose hypothesis_ = Pose::Identity();
  Utime hypothesis_t_ = 0;
  Pose T_map_odom_ = Pose::Identity();
  double path_at_match_m_ = 0.0;
  double var_t_ = 0.0, var_r_ = 0.0;  ///< variance of the current transform at the last anchor (m^2, rad^2)
  int gated_ = 0, ambiguous_ = 0;
  int frames_since_attempt_ = 0, attempts_ = 0, left_map_ = 0;
  Utime first_frame_ = -1, first_localised_ = -1;
  std::vector<KeyframePose> anchors_;
  double ms_ = 0.0;
};

}  // namespace livo
