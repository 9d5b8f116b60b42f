// Iterated ESIKF update with point-to-plane residuals against the voxel plane map
// (docs/algorithms.md section 2), and the degeneracy metric of the matched plane normals.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/worker_pool.hpp"
#include "livo/estimation/state.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/voxel_map.hpp"

#include <vector>

namespace livo {

struct LioConfig {
  int max_iterations = 5;
  double range_noise_m = 0.02;        ///< sigma_r of a LiDAR return (lidar.range_noise_m)
  double beam_noise_deg = 0.05;       ///< sigma_theta of a LiDAR return, degrees (lidar.beam_noise_deg)
  double residual_floor_var = 1e-4;   ///< m^2 added to every residual variance (FAST-LIVO2 uses 1e-3)
  double converge_rot_deg = 0.01;     ///< |dtheta| below this ...
  double converge_pos_m = 1.5e-4;     ///< ... and |dp| below this: converged
  double downsample_m = 0.1;          ///< voxel-grid leaf of the undistorted sweep, m
  int max_points = 20000;             ///< cap of downsampled points per frame (uniform subsampling beyond)

  /// Reads the `lio` section (and range/beam noise from the `lidar` section).
  void load(const ConfigNode& root);
};

/// One downsampled, undistorted point of the current sweep.
struct BodyPoint {
  Vec3 p_imu = Vec3::Zero();     ///< IMU frame at the frame time, m
  Mat3 cov_imu = Mat3::Zero();   ///< measurement covariance in the IMU frame, m^2
};

/// One residual row of the update: z = n^T (R p + t) + d.
struct PlaneResidual {
  Vec3 normal = Vec3::Zero();
  double residual = 0.0;    ///< signed distance, m
  double variance = 0.0;    ///< m^2
  Eigen::Matrix<double, 6, 1> h = Eigen::Matrix<double, 6, 1>::Zero();  ///< d z / d [dtheta, dp]
};

struct LioUpdateResult {
  int iterations = 0;
  bool converged = false;
  int matched = 0;                 ///< points with a plane at the final iteration
  std::vector<Vec3> matched_normals;  ///< plane normal of each matched point (final iteration)
  std::vector<int> matched_index;     ///< index into the input points, parallel to matched_normals
  double rms_residual_m = 0.0;
  // Consistency of the update (health.hpp), at the final iteration:
  int covered = 0;             ///< points whose root voxel holds a plane (matched or not)
  double nis = 0.0;            ///< mean z^2 / var over the matched points (their normalised innovation)
  /// (x_post [-] x_prop)^T P_prop^-1 (x_post [-] x_prop): how far the LiDAR moved the state from the
  /// IMU's prediction in the prediction's own sigmas (chi-square with at most 6 degrees of freedom
  /// when the filter is consistent: the measurement informs the pose).
  double correction_chi2 = 0.0;
  double correction_m = 0.0;    ///< |position part of x_post [-] x_prop|, m
};

/// Point-to-plane residual and its Jacobian for one point at state x (analytic):
///   z = n^T (R p_b + t) + d, dz/ddtheta = -n^T R [p_b]x = ([p_b]x R^T n)^T, dz/ddp = n^T.
PlaneResidual planeResidual(const NavState& x, const Vec3& p_imu, const Vec3& normal, double d);

/// World covariance of a body point: R S_b R^T + R [p]x P_thth [p]x^T R^T + P_pp (the reference code
/// omits R in the middle term; docs/algorithms.md section 2 [quirk]).
Mat3 worldPointCovariance(const NavState& x, const StateCov& P, const BodyPoint& bp);

/// worldPointCovariance for many points at one (x, P): the pose parts once. With q = R p,
/// R [p]x = [q]x R, so R [p]x P_thth [p]x^T R^T = [q]x S [q]x^T with S = R P_thth R^T.
class WorldPointCovariance {
 public:
  WorldPointCovariance(const NavState& x, const StateCov& P);
  /// The covariance of body point `bp`, whose rotated position R p_imu is `q` (inline: it runs per
  /// point and iteration in the association).
  Mat3 operator()(const BodyPoint& bp, const Vec3& q) const {
    const Mat3 Q = hat(q);
    return R_ * bp.cov_imu * R_.transpose() + Q * S_ * Q.transpose() + P_pp_;
  }

 private:
  Mat3 R_, S_, P_pp_;
};

/// Iterated update: re-associates every point with the map in every iteration (information form,
/// the candidate planes of a point kept while it stays in its voxel: CachedAssociation,
/// docs/algorithms.md section 2), then updates P once. `x`/`P` are the propagated prior on entry and the
/// posterior on return. With no match at all the state is left unchanged. With `pool`, the
/// association runs on its threads in fixed blocks summed in block order: the result is the same for
/// every thread count, and the same as without a pool.
LioUpdateResult lidarUpdate(NavState& x, StateCov& P, const std::vector<BodyPoint>& points, const PlaneFinder& map,
                            const LioConfig& cfg, WorkerPool* pool = nullptr);

/// Degeneracy metric (docs/algorithms.md "The two ideas", 1, and section 9): with M = sum n n^T over the N matched unit
/// normals (trace N) and lambda_min its smallest eigenvalue, sigma_min = sqrt(lambda_min / N), in
/// [0, 1/sqrt(3)] (1/sqrt(3) for three equally represented orthogonal plane families, 0 for parallel
/// planes; 0 for no normals). The paper's "normalize" admits two readings with this range; this one
/// and its threshold (selector.degeneracy_threshold) are discussed in docs/algorithms.md section 9.
double degeneracySigmaMin(const std::vector<Vec3>& normals);

}  // namespace livo
