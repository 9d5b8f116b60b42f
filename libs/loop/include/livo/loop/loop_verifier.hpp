// Geometric verification of a loop candidate: the query keyframe's points are registered against planes
// fitted to the candidate keyframe's points (a coarse search over yaw around the descriptor's guess, then
// Gauss-Newton point-to-plane), and the result is accepted only when enough points lie on the candidate's
// planes, their residual is as small as the sensor's noise allows, and it agrees with the odometry within
// the drift the path between the two allows. Every rejection is counted with its reason.
// docs/algorithms.md section 11, "Verification".
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/so3.hpp"
#include "livo/loop/place_descriptor.hpp"

#include <map>
#include <string>
#include <vector>

namespace livo {

struct LoopVerifyConfig {
  double voxel_m = 1.0;         ///< loop.verify_voxel_m: root voxel of the candidate's plane map
  double downsample_m = 0.5;    ///< loop.verify_downsample_m: the query's points, one per cube of this edge
  int max_iterations = 30;      ///< loop.verify_iterations: Gauss-Newton iterations at most
  /// loop.min_overlap: share of the query's thinned points on a candidate plane (true loops of the revisit
  /// scenario from livo-run's registered scans: 0.16-0.43; other places: 0.03)
  double min_overlap = 0.15;
  /// loop.max_residual_m: RMS point-to-plane distance of the matched points; default 3 sqrt(sigma_r^2 +
  /// min_eigen_value) with the LiDAR's range noise and the voxel map's plane thickness (0.0025 m^2).
  double max_rms_m = 0.0;
  double drift_fraction = 0.05;   ///< loop.max_drift_fraction: odometry drift allowed per metre between
  double drift_base_m = 2.0;      ///< loop.max_drift_m: plus this much (the place's own extent)
  double drift_yaw_deg_per_100m = 2.0;  ///< loop.max_drift_yaw_deg_per_100m
  double drift_yaw_base_deg = 5.0;      ///< loop.max_drift_yaw_deg
  double range_sigma_m = 0.02;     ///< lidar.range_noise_m (read by the LiDAR update; handed in)
  double bearing_sigma_deg = 0.1;  ///< lidar.beam_noise_deg (likewise)
  int min_points = 100;            ///< fewer (after thinning) on either side: rejected, too few points
  /// loop.min_sigma: the matched planes' normals must constrain every direction: sqrt(lambda_min / N) of
  /// sum n n^T over the N matched points (the LiDAR update's degeneracy metric, selector.degeneracy_threshold)
  /// at least this, else rejected as degenerate (a corridor or a wall lets the registration slide along it;
  /// the simulator's corridor gives 0.011, its street frames 0.28 and more, the revisit block 0.14 and more)
  double min_sigma = 0.08;
  /// Two keyframes whose odometry puts them farther apart than this plus the drift bound cannot be one
  /// place: rejected as inconsistent before any registration (LoopConfig sets the descriptor's range).
  double max_place_offset_m = 40.0;

  /// Reads the verification keys of the `loop` section; the LiDAR's noise comes from its own section.
  void load(const ConfigNode& loop, double range_sigma_m, double bearing_sigma_deg);
  /// max_rms_m, or its default when 0.
  double maxRms() const;
};

enum class LoopReject { None, TooFewPoints, NoConvergence, LowOverlap, HighResidual, Degenerate, Inconsistent };
const char* toString(LoopReject r);

struct LoopCheck {
  bool accepted = false;
  LoopReject reason = LoopReject::TooFewPoints;
  /// The query keyframe's frame in the candidate's: q_cand = T_cand_query q_query.
  Pose T_cand_query = Pose::Identity();
  double overlap = 0.0;  ///< share of the query's thinned points matched to a plane at the end
  double rms_m = 0.0;    ///< RMS distance of the matched points to their planes
  double sigma_min = 0.0;  ///< the matched normals' degeneracy metric (LoopVerifyConfig::min_sigma)
  int iterations = 0;
  double odometry_gap_m = 0.0, odometry_gap_deg = 0.0;  ///< against the odometry's relative pose
};

/// Counts of the checks by outcome.
struct LoopCheckCounts {
  int accepted = 0, too_few_points = 0, no_convergence = 0, low_overlap = 0, high_residual = 0, degenerate = 0,
      inconsistent = 0;
  int total() const {
    return accepted + too_few_points + no_convergence + low_overlap + high_residual + degenerate + inconsistent;
  }
  /// PREFIX_checks, PREFIX_accepted and PREFIX_rejected_<reason> into stats.json counters.
  void addCounters(const std::string& prefix, std::map<std::string, double>& c) const;
};

class LoopVerifier {
 public:
  explicit LoopVerifier(LoopVerifyConfig cfg) : cfg_(cfg) {}
  /// Checks one candidate. Points are in their keyframe frames (gravity-aligned, heading along x, origin
  /// at the sensor: place_descriptor.hpp); `yaw_guess` is PlaceMatch::yaw_rad (q_query ~= Rz(yaw) q_cand);
  /// `T_odom_cand_query` the odometry's relative pose of the two keyframe frames and `path_between_m`
  /// the travel between them, which bound the drift the loop may correct.
  LoopCheck verify(const std::vector<Vec3>& cand_points, const std::vector<Vec3>& query_points, double yaw_guess,
                   const Pose& T_odom_cand_query, double path_between_m);
  const LoopCheckCounts& counts() const { return counts_; }

 private:
  LoopVerifyConfig cfg_;
  LoopCheckCounts counts_;
  LoopCheck finish(LoopCheck c);
};

/// Thins `points` to the first of each cube of edge `voxel_m` (in input order).
std::vector<Vec3> thinPoints(const std::vector<Vec3>& points, double voxel_m);

}  // namespace livo
