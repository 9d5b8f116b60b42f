// Trajectory error metrics on associated, aligned pose pairs.
//
// ATE (absolute trajectory error, Sturm et al. IROS 2012 eq. 1-2): per pair the position error
// |p_gt - p_est_aligned| (m) and the rotation error angle(R_gt^T R_est_aligned) (deg).
// RPE (relative pose error, KITTI-style over travelled distance, Geiger et al. CVPR 2012): for every
// start pair i, j is the first pair whose ground-truth distance along the path from i reaches delta;
// E_ij = (T_gt_i^-1 T_gt_j)^-1 (T_est_i^-1 T_est_j). Reported both absolute (|trans(E)| in m,
// angle(E) in deg) and normalised by delta (percent and deg/m, the KITTI convention).
#pragma once

#include "livo/common/so3.hpp"

#include <cstddef>
#include <vector>

namespace livo {

/// Summary of a series of non-negative errors.
struct ErrorStats {
  std::size_t count = 0;
  double rmse = 0, mean = 0, median = 0, max = 0, min = 0, std = 0;
};
/// rmse, mean, median (mean of the two middle values for even counts), max, min, population std;
/// all zeros for an empty series.
ErrorStats errorStats(std::vector<double> errors);

struct AteResult {
  ErrorStats translation_m;
  ErrorStats rotation_deg;
};
/// Per-pair ATE between gt[i] and est_aligned[i] (same sizes; throws std::invalid_argument otherwise).
AteResult computeAte(const std::vector<Pose>& gt, const std::vector<Pose>& est_aligned);

struct RpeResult {
  double delta_m = 0;           ///< requested distance
  ErrorStats translation_m;     ///< |trans(E_ij)|
  ErrorStats rotation_deg;      ///< angle(E_ij)
  double translation_pct = 0;   ///< mean |trans(E_ij)| / delta * 100
  double rotation_deg_per_m = 0;///< mean angle(E_ij) / delta
};
/// RPE over the distance `delta_m` (> 0; throws std::invalid_argument otherwise). Pairs with no j
/// far enough along the path are skipped; count == 0 when the path is shorter than delta.
/// Independent of a rigid alignment of est; est positions should carry the estimated scale.
RpeResult computeRpe(const std::vector<Pose>& gt, const std::vector<Pose>& est, double delta_m);

/// Sum of |p_{k+1} - p_k| (m).
double pathLength(const std::vector<Vec3>& positions);
/// Cumulative distance along the path, d[0] = 0.
std::vector<double> cumulativeDistance(const std::vector<Vec3>& positions);

/// Default RPE distances for a path of the given length: 10 %, 25 % and 50 % of it, each rounded
/// down to 1, 2 or 5 x 10^k m, duplicates removed; empty for a path shorter than 1 mm.
std::vector<double> defaultRpeDeltas(double path_length_m);

}  // namespace livo
