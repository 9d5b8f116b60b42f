#include "livo/eval/evaluate.hpp"

#include "livo/common/config.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace livo {

void EvalConfig::load(const ConfigNode& node) {
  node.get("max_dt_s", max_dt_s).get("est_time_offset_s", est_time_offset_s).get("with_scale", with_scale);
  node.get("rpe_deltas_m", rpe_deltas_m);
  int min_pairs = static_cast<int>(min_matched);
  node.get("min_matched", min_pairs);
  node.check(min_pairs >= 3, "min_matched", "must be >= 3");
  min_matched = static_cast<std::size_t>(min_pairs);
  node.check(std::isfinite(max_dt_s) && max_dt_s >= 0, "max_dt_s", "must be a finite value >= 0");
  node.check(std::isfinite(est_time_offset_s), "est_time_offset_s", "must be finite");
  for (double d : rpe_deltas_m) node.check(std::isfinite(d) && d > 0, "rpe_deltas_m", "every delta must be > 0");
}

void EvalConfig::validate() const {
  if (!(std::isfinite(max_dt_s) && max_dt_s >= 0))
    throw std::invalid_argument("max_dt_s must be a finite value >= 0");
  if (!std::isfinite(est_time_offset_s)) throw std::invalid_argument("est_time_offset_s must be finite");
  for (double d : rpe_deltas_m)
    if (!(std::isfinite(d) && d > 0)) throw std::invalid_argument("rpe_deltas_m: every delta must be > 0");
  if (min_matched < 3) throw std::invalid_argument("min_matched must be >= 3 (alignment needs 3 points)");
}

EvalResult evaluate(const Trajectory& gt, const Trajectory& est, const EvalConfig& config) {
  config.validate();
  if (gt.empty()) throw std::runtime_error("ground truth has no poses");
  if (est.empty()) throw std::runtime_error("estimate has no poses");

  // 1. Associate by nearest timestamp.
  const std::vector<PosePair> pairs = associate(gt, est, config.max_dt_s, config.est_time_offset_s);
  if (pairs.size() < config.min_matched) {
    std::ostringstream msg;
    msg.precision(15);
    msg << (pairs.empty() ? "no overlap" : "too few matched poses") << ": " << pairs.size()
        << " pose pairs within max_dt " << config.max_dt_s << " s (need " << config.min_matched
        << "); ground truth spans [" << gt.front().t << ", " << gt.back().t << "] s, estimate spans ["
        << est.front().t + config.est_time_offset_s << ", " << est.back().t + config.est_time_offset_s << "] s";
    if (config.est_time_offset_s != 0.0) msg << " after the time offset " << config.est_time_offset_s << " s";
    throw std::runtime_error(msg.str());
  }

  EvalResult r;
  r.gt_poses = gt.size();
  r.est_poses = est.size();
  r.matched = pairs.size();
  std::vector<Pose> gt_matched, est_matched;
  std::vector<Vec3> p_gt, p_est;
  double sum_dt = 0;
  for (const PosePair& pair : pairs) {
    gt_matched.push_back(gt[pair.gt_index].T_world_body);
    est_matched.push_back(est[pair.est_index].T_world_body);
    p_gt.push_back(gt_matched.back().translation());
    p_est.push_back(est_matched.back().translation());
    sum_dt += std::abs(gt[pair.gt_index].t - (est[pair.est_index].t + config.est_time_offset_s));
  }
  r.mean_abs_dt_s = sum_dt / double(pairs.size());
  r.matched_duration_s = gt[pairs.back().gt_index].t - gt[pairs.front().gt_index].t;

  // 2. Ground-truth path length over the matched span, on every ground-truth pose in it.
  std::vector<Vec3> p_span;
  for (std::size_t k = pairs.front().gt_index; k <= pairs.back().gt_index; ++k)
    p_span.push_back(gt[k].T_world_body.translation());
  r.path_length_m = pathLength(p_span);

  // 3. Align the estimate onto the ground truth (Umeyama on positions), unless the alignment is given.
  r.T_gt_est = config.fixed_alignment ? *config.fixed_alignment : umeyama(p_est, p_gt, config.with_scale);
  std::vector<Pose> est_aligned;
  est_aligned.reserve(est_matched.size());
  for (const Pose& T : est_matched) est_aligned.push_back(r.T_gt_est.apply(T));

  // 4. ATE and RPE.
  r.ate = computeAte(gt_matched, est_aligned);
  const std::vector<double> deltas =
      config.rpe_deltas_m.empty() ? defaultRpeDeltas(r.path_length_m) : config.rpe_deltas_m;
  for (double delta : deltas) r.rpe.push_back(computeRpe(gt_matched, est_aligned, delta));
  return r;
}

}  // namespace livo
