#include "livo/sensors/preprocess_points.hpp"

#include <algorithm>
#include <cmath>

namespace livo {

Utime filterScanPoints(const LidarScan& scan, Utime start_utime, const PreprocessConfig& cfg,
                       PreprocessStats& stats, std::vector<StampedPoint>& out) {
  stats.points_in += scan.points.size();
  const double blind2 = cfg.blind_m * cfg.blind_m;
  const double range2 = cfg.max_range_m * cfg.max_range_m;
  const auto decimation = static_cast<unsigned>(std::max(1, cfg.point_filter_num));
  unsigned passed = 0;
  float latest_offset = 0.f;
  bool any_valid_time = false;
  out.reserve(out.size() + scan.points.size() / decimation + 1);

  for (const LidarPoint& p : scan.points) {
    if (!p.p_lidar.allFinite() || !std::isfinite(p.time_offset_s)) {
      ++stats.points_nan;
      continue;
    }
    if (std::abs(p.time_offset_s) > cfg.max_point_offset_s) {
      ++stats.points_bad_time;
      continue;
    }
    latest_offset = any_valid_time ? std::max(latest_offset, p.time_offset_s) : p.time_offset_s;
    any_valid_time = true;
    const double r2 = p.p_lidar.cast<double>().squaredNorm();
    if (r2 < blind2) {
      ++stats.points_blind;
      continue;
    }
    if (r2 > range2) {
      ++stats.points_range;
      continue;
    }
    if (passed++ % decimation != 0) {
      ++stats.points_decimated;
      continue;
    }
    out.push_back({p, start_utime + fromSeconds(p.time_offset_s)});
  }
  return any_valid_time ? std::max(start_utime, start_utime + fromSeconds(latest_offset)) : start_utime;
}

}  // namespace livo
