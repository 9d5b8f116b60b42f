// Text and JSON output of an EvalResult.
#include "livo/eval/report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace livo {
namespace {

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

// Minimal JSON object writer: keys are fixed ASCII identifiers, so no escaping is needed for them.
class JsonObject {
 public:
  JsonObject& field(const char* key, const std::string& raw_value) {
    out_ << (first_ ? "" : ", ") << '"' << key << "\": " << raw_value;
    first_ = false;
    return *this;
  }
  JsonObject& number(const char* key, double v) { return field(key, num(v)); }
  JsonObject& count(const char* key, std::size_t v) { return field(key, std::to_string(v)); }
  JsonObject& boolean(const char* key, bool v) { return field(key, v ? "true" : "false"); }
  std::string str() const { return "{" + out_.str() + "}"; }

 private:
  std::ostringstream out_;
  bool first_ = true;
};

std::string array(const double* v, std::size_t n) {
  std::string s = "[";
  for (std::size_t i = 0; i < n; ++i) s += (i ? ", " : "") + num(v[i]);
  return s + "]";
}

}  // namespace

std::string toJson(const EvalResult& r, const EvalConfig& config) {
  const std::array<double, 7> T = poseToArray(r.T_gt_est.rigid());
  std::string rpe = "[";
  for (std::size_t k = 0; k < r.rpe.size(); ++k) {
    const RpeResult& e = r.rpe[k];
    JsonObject o;
    o.number("delta_m", e.delta_m).count("pairs", e.translation_m.count);
    o.number("trans_rmse_m", e.translation_m.rmse).number("trans_mean_m", e.translation_m.mean);
    o.number("trans_median_m", e.translation_m.median).number("trans_max_m", e.translation_m.max);
    o.number("trans_pct", e.translation_pct);
    o.number("rot_rmse_deg", e.rotation_deg.rmse).number("rot_mean_deg", e.rotation_deg.mean);
    o.number("rot_max_deg", e.rotation_deg.max).number("rot_deg_per_m", e.rotation_deg_per_m);
    rpe += (k ? ", " : "") + o.str();
  }
  rpe += "]";

  JsonObject o;
  o.number("ate_rmse_m", r.ate.translation_m.rmse).number("ate_mean_m", r.ate.translation_m.mean);
  o.number("ate_median_m", r.ate.translation_m.median).number("ate_max_m", r.ate.translation_m.max);
  o.number("ate_min_m", r.ate.translation_m.min).number("ate_std_m", r.ate.translation_m.std);
  o.number("ate_rot_rmse_deg", r.ate.rotation_deg.rmse).number("ate_rot_mean_deg", r.ate.rotation_deg.mean);
  o.number("ate_rot_median_deg", r.ate.rotation_deg.median).number("ate_rot_max_deg", r.ate.rotation_deg.max);
  o.count("matched", r.matched).count("gt_poses", r.gt_poses).count("est_poses", r.est_poses);
  o.number("path_length_m", r.path_length_m).number("duration_s", r.matched_duration_s);
  o.number("mean_abs_dt_s", r.mean_abs_dt_s).number("max_dt_s", config.max_dt_s);
  o.number("time_offset_s", config.est_time_offset_s);
  o.boolean("scale_estimated", config.with_scale).number("scale", r.T_gt_est.s);
  o.boolean("alignment_fixed", config.fixed_alignment.has_value());
  o.field("T_gt_est", array(T.data(), T.size()));
  o.field("rpe", rpe);
  return o.str();
}

std::string toText(const EvalResult& r, const EvalConfig& config) {
  const std::array<double, 7> T = poseToArray(r.T_gt_est.rigid());
  char buf[512];
  std::ostringstream out;
  std::snprintf(buf, sizeof(buf), "matched      %zu of %zu estimated poses (%zu ground truth), max_dt %.4g s\n",
                r.matched, r.est_poses, r.gt_poses, config.max_dt_s);
  out << buf;
  std::snprintf(buf, sizeof(buf), "path length  %.3f m over %.3f s\n", r.path_length_m, r.matched_duration_s);
  out << buf;
  std::snprintf(buf, sizeof(buf),
                "alignment    %s, T_gt_est t = [%.4f %.4f %.4f] m, q = [%.5f %.5f %.5f %.5f], scale %.6f\n",
                config.fixed_alignment ? "fixed (--align-like)" : config.with_scale ? "Sim(3)" : "SE(3)", T[0], T[1], T[2], T[3], T[4], T[5], T[6], r.T_gt_est.s);
  out << buf;
  const ErrorStats& a = r.ate.translation_m;
  std::snprintf(buf, sizeof(buf), "ATE trans    rmse %.4f  mean %.4f  median %.4f  max %.4f  (m)\n", a.rmse,
                a.mean, a.median, a.max);
  out << buf;
  const ErrorStats& b = r.ate.rotation_deg;
  std::snprintf(buf, sizeof(buf), "ATE rot      rmse %.4f  mean %.4f  median %.4f  max %.4f  (deg)\n", b.rmse,
                b.mean, b.median, b.max);
  out << buf;
  for (const RpeResult& e : r.rpe) {
    if (e.translation_m.count == 0) {
      std::snprintf(buf, sizeof(buf), "RPE %7.3g m  no pair (path too short)\n", e.delta_m);
    } else {
      std::snprintf(buf, sizeof(buf),
                    "RPE %7.3g m  %5zu pairs  trans rmse %.4f m (%.3f %%)  rot rmse %.4f deg (%.5f deg/m)\n",
                    e.delta_m, e.translation_m.count, e.translation_m.rmse, e.translation_pct, e.rotation_deg.rmse,
                    e.rotation_deg_per_m);
    }
    out << buf;
  }
  return out.str();
}

}  // namespace livo
