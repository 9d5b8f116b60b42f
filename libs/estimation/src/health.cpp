#include "livo/estimation/health.hpp"

#include <algorithm>
#include <cmath>
#include <vector>
#include <iomanip>
#include <sstream>

namespace livo {

void HealthConfig::load(const ConfigNode& health) {
  health.get("correction_chi2_max", correction_chi2_max).get("min_match_share", min_match_share);
  health.get("window_s", window_s).get("max_speed_mps", max_speed_mps).get("recover", recover);
  health.check(correction_chi2_max > 0, "correction_chi2_max", "must be > 0");
  health.check(min_match_share >= 0 && min_match_share <= 1, "min_match_share", "must be in [0, 1]");
  health.check(window_s > 0, "window_s", "must be > 0");
  health.check(max_speed_mps > 0, "max_speed_mps", "must be > 0");
}

const char* healthName(HealthState s) {
  switch (s) {
    case HealthState::Initialising: return "initialising";
    case HealthState::Ok: return "ok";
    case HealthState::Degraded: return "degraded";
    case HealthState::Lost: return "lost";
  }
  return "unknown";
}

void HealthMonitor::recovered(Utime t) {
  lost_ = false;
  window_.clear();
  shares_.clear();
  lost_span_ = {-1, -1};
  last_inconsistent_ = t;
}

double HealthMonitor::referenceShare() const {
  if (shares_.size() < 3) return -1.0;
  std::vector<double> v;
  v.reserve(shares_.size());
  for (const auto& s : shares_) v.push_back(s.second);
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
  return v[v.size() / 2];
}

FrameHealth HealthMonitor::assess(const HealthInputs& in) {
  FrameHealth h;
  if (!in.initialized) return h;
  std::ostringstream why;
  why << std::setprecision(3);
  const auto add = [&](const auto&... parts) {
    if (why.tellp() > 0) why << "; ";
    (why << ... << parts);
  };
  bool speed_out = false;
  if (!(in.speed_mps <= cfg_.max_speed_mps)) {
    speed_out = true;
    add("speed ", in.speed_mps, " m/s above ", cfg_.max_speed_mps);
  }
  if (in.update_ran && in.correction_chi2 > cfg_.correction_chi2_max) {
    h.inconsistent = in.correction_m > in.plane_sigma_m;
    add("LiDAR correction chi2 ", in.correction_chi2, " above ", cfg_.correction_chi2_max, " (", 100.0 * in.correction_m,
        " cm)");
  }
  const double ref = referenceShare();
  if (in.update_ran && in.n_covered >= in.min_matches && ref > 0 &&
      double(in.n_matched) < cfg_.min_match_share * ref * double(in.n_covered)) {
    h.inconsistent = true;
    add("matched ", in.n_matched, " of ", in.n_covered, " covered points (usually ", ref, ")");
  }
  if (in.repeated_sweep) add("the sweep repeats the previous one point for point (a frozen LiDAR): not used");
  else if (in.lidar_failed) add(in.visual_used ? "LiDAR update failed (camera used)" : "LiDAR update failed (IMU only)");
  h.inconsistent = h.inconsistent || speed_out;

  // The persistence rule over the last window_s seconds.
  const Utime window = Utime(std::llround(cfg_.window_s * 1e6));
  window_.emplace_back(in.utime, h.inconsistent);
  while (!window_.empty() && window_.front().first <= in.utime - window) window_.pop_front();
  std::size_t bad = 0;
  for (const auto& w : window_) bad += w.second;
  if (h.inconsistent) last_inconsistent_ = in.utime;
  if (!h.inconsistent && in.update_ran && in.n_covered >= in.min_matches) {
    shares_.emplace_back(in.utime, double(in.n_matched) / double(in.n_covered));
    while (shares_.front().first <= in.utime - 4 * window) shares_.pop_front();
  }
  if (speed_out || (bad >= 3 && 2 * bad >= window_.size())) {
    if (!lost_) {  // the span starts at the first inconsistent frame of the window
      lost_since_ = in.utime;
      for (const auto& w : window_)
        if (w.second) {
          lost_since_ = w.first;
          break;
        }
    }
    lost_ = true;
  } else if (lost_ && in.utime - last_inconsistent_ >= window) {
    lost_ = false;
    lost_span_ = {lost_since_, last_inconsistent_};
  }

  if (lost_) {
    h.state = HealthState::Lost;
    if (!h.inconsistent) add("no ", cfg_.window_s, " s without an inconsistent frame yet");
  } else if (lost_span_.first >= 0) {
    // Consistent again, but nothing ties the frame to where it was before the lost span: the
    // trajectory may carry the span's error from here on.
    add("not re-anchored since the lost span at ", std::fixed, std::setprecision(2), toSeconds(lost_span_.first), "-",
        toSeconds(lost_span_.second), " s");
    h.state = HealthState::Degraded;
  } else {
    h.state = why.tellp() > 0 ? HealthState::Degraded : HealthState::Ok;
  }
  h.reason = why.str();
  return h;
}

}  // namespace livo
