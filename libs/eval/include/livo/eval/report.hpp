// Output of an evaluation: one JSON object (livo-eval --json) or a short text report.
#pragma once

#include "livo/eval/evaluate.hpp"

#include <string>

namespace livo {

/// One JSON object on one line. Keys: ate_{rmse,mean,median,max,min,std}_m,
/// ate_rot_{rmse,mean,median,max}_deg, matched, gt_poses, est_poses, path_length_m, duration_s,
/// mean_abs_dt_s, max_dt_s, time_offset_s, scale_estimated, scale, T_gt_est [x,y,z,qx,qy,qz,qw],
/// rpe [{delta_m, pairs, trans_{rmse,mean,median,max}_m, trans_pct, rot_{rmse,mean,max}_deg,
/// rot_deg_per_m}]. Non-finite numbers are written as null.
std::string toJson(const EvalResult& r, const EvalConfig& config);
/// Human-readable multi-line report.
std::string toText(const EvalResult& r, const EvalConfig& config);

}  // namespace livo
