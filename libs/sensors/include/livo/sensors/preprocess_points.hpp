// Per-scan point filtering: validity, blind zone, range, decimation, absolute point times.
#pragma once

#include "livo/common/types.hpp"
#include "livo/sensors/preprocess_config.hpp"
#include "livo/sensors/preprocess_stats.hpp"

#include <vector>

namespace livo {

/// A LiDAR point with its absolute time (sensor clock, µs). `point.time_offset_s` is not used while
/// the point is buffered; it is rewritten relative to the sweep start when a frame is cut.
struct StampedPoint {
  LidarPoint point;
  Utime utime = 0;
};

/// Filters the points of `scan` in this order, each step counting what it drops in `stats`:
///   1. non-finite coordinates or time offset (points_nan);
///   2. |time_offset_s| > max_point_offset_s (points_bad_time);
///   3. |p| < blind_m (points_blind), then |p| > max_range_m (points_range);
///   4. decimation: of the points left, the k-th (k = 0, 1, ...) is kept when k % point_filter_num == 0
///      (points_decimated).
/// Kept points are appended to `out` in input order with utime = start_utime + round(offset, µs).
/// Adds the scan size to stats.points_in. Returns the LiDAR coverage time: the latest valid point time
/// (steps 1-2 passed, range filters ignored), or start_utime when there is none.
Utime filterScanPoints(const LidarScan& scan, Utime start_utime, const PreprocessConfig& cfg,
                       PreprocessStats& stats, std::vector<StampedPoint>& out);

}  // namespace livo
