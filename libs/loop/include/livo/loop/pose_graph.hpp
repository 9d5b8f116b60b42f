// The pose graph of keyframes: odometry edges between consecutive keyframes, loop edges from verified loops
// (robust loss), solved with Ceres; the optimised keyframe poses are the map frame, and the correction
// T_map_odom of the newest keyframe carries the odometry into it. docs/algorithms.md section 11, "Pose graph".
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/so3.hpp"

#include <string>
#include <vector>

namespace livo {

struct PoseGraphConfig {
  /// loop.odometry_sigma_fraction: position sigma of an odometry edge per metre of its length (plus 1 cm)
  double odometry_sigma_fraction = 0.01;
  /// loop.odometry_sigma_deg_per_m: rotation sigma of an odometry edge per metre (plus 0.05 deg)
  double odometry_sigma_deg_per_m = 0.05;
  double loop_sigma_m = 0.05;    ///< loop.loop_sigma_m: position sigma of a verified loop
  double loop_sigma_deg = 0.5;   ///< loop.loop_sigma_deg: its rotation sigma
  /// loop.loop_robust_sigmas: the Cauchy loss of a loop edge's whitened error has this scale (sigmas);
  /// 0 turns the robust loss off
  double loop_robust_sigmas = 3.0;
  int max_iterations = 100;      ///< loop.graph_iterations: Levenberg-Marquardt iterations at most
  void load(const ConfigNode& loop);
  /// Sigmas of `length_m` of odometry: position (m) and rotation (rad).
  double odometrySigmaM(double length_m) const { return 0.01 + odometry_sigma_fraction * length_m; }
  double odometrySigmaRad(double length_m) const {
    return (0.05 + odometry_sigma_deg_per_m * length_m) * 3.14159265358979323846 / 180.0;
  }
};

struct PoseGraphEdge {
  int from = 0, to = 0;
  Pose T_from_to = Pose::Identity();  ///< measured pose of `to` in `from`
  bool loop = false;
};

struct PoseGraphReport {
  bool solved = false;
  int iterations = 0;
  std::string message;  ///< Ceres' summary line when not solved
};

class PoseGraph {
 public:
  explicit PoseGraph(PoseGraphConfig cfg = {}) : cfg_(cfg) {}
  /// Adds a keyframe at its odometry pose and, from the second on, the odometry edge from the one
  /// before; returns its index. Its map-frame pose starts as the odometry pose carried by the newest
  /// correction, so that a graph solved before keeps its frame.
  int addKeyframe(const Pose& T_odom_key);
  /// A verified loop: the pose of keyframe `to` in keyframe `from`.
  void addLoop(int from, int to, const Pose& T_from_to);
  /// Optimises every keyframe pose but the first (held: it fixes the map frame).
  PoseGraphReport optimize();

  std::size_t size() const { return odom_.size(); }
  const Pose& odometryPose(int i) const { return odom_.at(static_cast<std::size_t>(i)); }
  /// The keyframe's pose in the map frame (the odometry's until a loop is optimised).
  const Pose& mapPose(int i) const { return map_.at(static_cast<std::size_t>(i)); }
  /// T_map_odom: mapPose(last) * odometryPose(last)^-1 as of the last solve that moved the poses
  /// (identity before); keyframes added since are placed with it.
  const Pose& correction() const { return correction_; }
  int loops() const { return loops_; }

 private:
  PoseGraphConfig cfg_;
  std::vector<Pose> odom_, map_;
  Pose correction_ = Pose::Identity();
  std::vector<PoseGraphEdge> edges_;
  int loops_ = 0;
};

}  // namespace livo
