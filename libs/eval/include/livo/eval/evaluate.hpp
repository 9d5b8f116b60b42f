// The whole evaluation of an estimated trajectory against ground truth: associate by time, align
// (Umeyama SE(3), or Sim(3) with scale), ATE, RPE, path length. livo-eval is a thin CLI around it.
#pragma once

#include "livo/eval/align.hpp"
#include "livo/eval/metrics.hpp"
#include "livo/eval/tum.hpp"

#include <string>
#include <optional>
#include <vector>

namespace livo {

class ConfigNode;

struct EvalConfig {
  double max_dt_s = 0.01;           ///< association: max |t_gt - t_est| (s)
  double est_time_offset_s = 0.0;   ///< added to estimated times before association (s)
  bool with_scale = false;          ///< Sim(3) alignment (monocular); SE(3) otherwise
  std::vector<double> rpe_deltas_m; ///< RPE distances (m); empty = defaultRpeDeltas(path length)
  std::size_t min_matched = 3;      ///< fewer matched pairs is an error
  /// Set: the estimate is mapped with this instead of being aligned (e.g. the alignment of another run
  /// in the same frame: the error of a map-frame trajectory without aligning it). Not a config key.
  std::optional<Sim3> fixed_alignment;

  /// Keys: max_dt_s, est_time_offset_s, with_scale, rpe_deltas_m, min_matched.
  void load(const ConfigNode& node);
  /// Throws std::invalid_argument naming the field on a bad value.
  void validate() const;
};

struct EvalResult {
  std::size_t gt_poses = 0, est_poses = 0, matched = 0;
  double matched_duration_s = 0;  ///< time span of the matched ground-truth poses
  double path_length_m = 0;       ///< ground-truth path length over the matched time span (all gt poses)
  double mean_abs_dt_s = 0;       ///< mean |t_gt - t_est| over the matched pairs
  Sim3 T_gt_est;                  ///< alignment: p_gt ~= s R p_est + t
  AteResult ate;
  std::vector<RpeResult> rpe;
};

/// Throws std::runtime_error with a clear message when nothing overlaps in time or too few poses
/// match (the message gives both time spans and max_dt).
EvalResult evaluate(const Trajectory& gt, const Trajectory& est, const EvalConfig& config);

}  // namespace livo
