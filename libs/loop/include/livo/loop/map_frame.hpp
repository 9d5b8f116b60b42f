// The loop closure's map frame as its consumers see it (livo-run --loop, livo-exporter, livo-viewer):
// the keyframes with their times, odometry poses and map-frame poses, and the loop edges, sent by the
// loop closer as corrections (livo_map_correction_t between processes), and the odometry's frames
// carried into the map frame by the keyframe at or before them. docs/algorithms.md section 11.
#pragma once

#include "livo/common/so3.hpp"
#include "livo/common/types.hpp"

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace livo {

struct KeyframePose {
  Utime utime = 0;
  Pose T_odom = Pose::Identity();  ///< the keyframe's frame in the odometry frame (graph node, as added)
  Pose T_map = Pose::Identity();   ///< the same frame in the map frame (the graph's latest solve)
};

/// What the loop closer tells its consumers after a keyframe: the newest correction, the keyframes
/// [first, first + keyframes.size()) of the graph (all of them after a solve, the new one otherwise) and
/// every loop edge so far.
struct MapCorrection {
  Utime utime = 0;                       ///< the odometry frame that made the newest keyframe
  Pose T_map_odom = Pose::Identity();    ///< the odometry frame in the map frame, for frames after it
  std::int32_t keyframes_total = 0;      ///< keyframes in the graph
  std::int32_t first = 0;                ///< graph index of keyframes[0]
  std::vector<KeyframePose> keyframes;
  std::vector<std::pair<std::int32_t, std::int32_t>> loops;  ///< (earlier, later) keyframe indices
  std::int32_t solves = 0;               ///< graph solves so far
  bool final = false;                    ///< sent at the loop closer's exit (after its last solve)
};

/// The consumers' copy of the keyframes. Corrections may arrive with gaps (a lost message, a consumer
/// started late): a frame is then carried by the nearest known keyframe at or before it.
class MapFrameTrajectory {
 public:
  /// Takes the keyframes of `c` (replacing those it already had) and its loop edges. Returns "" or,
  /// when `c` is inconsistent with what came before (a keyframe time changed: another run), why it was
  /// refused; nothing is changed then.
  std::string apply(const MapCorrection& c);
  /// The map-frame pose of a frame at `t` with odometry pose `T_odom` (T_map * T_odom^-1 of the last
  /// known keyframe at or before `t`, times `T_odom`); nullopt before the first keyframe.
  std::optional<Pose> toMap(Utime t, const Pose& T_odom) const;
  std::size_t known() const { return keyframes_.size(); }
  std::int32_t total() const { return total_; }
  /// Known keyframes by graph index, and the loop edges.
  const std::map<std::int32_t, KeyframePose>& keyframes() const { return keyframes_; }
  const std::vector<std::pair<std::int32_t, std::int32_t>>& loops() const { return loops_; }
  bool sawFinal() const { return final_; }

 private:
  std::map<std::int32_t, KeyframePose> keyframes_;
  std::map<Utime, Pose> carry_;  ///< per known keyframe time: T_map * T_odom^-1
  std::vector<std::pair<std::int32_t, std::int32_t>> loops_;
  std::int32_t total_ = 0;
  bool final_ = false;
};

}  // namespace livo
