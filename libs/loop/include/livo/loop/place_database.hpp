// Keyframes and the search over them: a keyframe every few metres or degrees of the odometry, stored with
// its pose, the path travelled and its place descriptor; a query returns the stored keyframes that look like the
// current place, each with the yaw between them, for geometric verification. docs/algorithms.md,
// "Place recognition".
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/so3.hpp"
#include "livo/common/types.hpp"
#include "livo/loop/place_descriptor.hpp"

#include <vector>

namespace livo {

struct KeyframeConfig {
  double distance_m = 2.0;  ///< loop.keyframe_distance_m: a keyframe after this much travel
  double angle_deg = 20.0;  ///< loop.keyframe_angle_deg: or after this much turn
  void load(const ConfigNode& loop);
};

/// Decides which odometry poses become keyframes and measures the path travelled.
class KeyframeSelector {
 public:
  explicit KeyframeSelector(KeyframeConfig cfg) : cfg_(cfg) {}
  /// Takes the next pose of the odometry; true when it is a keyframe (the first pose, or moved
  /// distance_m or turned angle_deg since the last keyframe).
  bool offer(const Pose& T_world_body);
  /// Metres travelled along the poses offered so far.
  double pathLength() const { return path_m_; }

 private:
  KeyframeConfig cfg_;
  bool have_last_ = false, have_key_ = false;
  Pose last_ = Pose::Identity();
  Pose key_ = Pose::Identity();
  double path_m_ = 0.0;
};

struct PlaceSearchConfig {
  int ring_candidates = 10;     ///< loop.search_candidates: nearest ring keys compared in full
  double max_distance = 0.3;    ///< loop.match_distance: descriptor distance a candidate must stay below
  /// loop.min_loop_path_m: a stored keyframe is a candidate only after this much travel since it was
  /// stored (a place must be left before it can be come back to); default twice the descriptor's range.
  double min_path_m = 0.0;
  void load(const ConfigNode& loop, const PlaceDescriptorConfig& descriptor);
};

struct PlaceEntry {
  Utime utime = 0;
  double path_m = 0.0;  ///< KeyframeSelector::pathLength() when stored
  Pose T_world_body = Pose::Identity();
  PlaceDescriptor descriptor;
};

struct PlaceCandidate {
  int id = -1;  ///< index into the database
  double ring_key_distance = 0.0;
  PlaceMatch match;
};

class PlaceDatabase {
 public:
  explicit PlaceDatabase(PlaceSearchConfig cfg) : cfg_(cfg) {}
  /// Stores a keyframe; returns its id (the count before).
  int add(PlaceEntry e);
  /// Keyframes that look like `query`, taken at `path_m` of travel: among those stored at least
  /// min_path_m earlier, the ring_candidates nearest ring keys, compared at every yaw; those below
  /// max_distance, best first.
  std::vector<PlaceCandidate> search(const PlaceDescriptor& query, double path_m) const;
  const PlaceEntry& entry(int id) const { return entries_.at(static_cast<std::size_t>(id)); }
  std::size_t size() const { return entries_.size(); }

 private:
  PlaceSearchConfig cfg_;
  std::vector<PlaceEntry> entries_;
};

}  // namespace livo
