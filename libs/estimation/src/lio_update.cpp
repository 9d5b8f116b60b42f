#include "livo/estimation/lio_update.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>

namespace livo {

void LioConfig::load(const ConfigNode& root) {
  const ConfigNode lidar = root.section("lidar");
  lidar.get("range_noise_m", range_noise_m).get("beam_noise_deg", beam_noise_deg);
  const ConfigNode n = root.section("lio");
  n.get("max_iterations", max_iterations).get("residual_floor_var", residual_floor_var);
  n.get("converge_rot_deg", converge_rot_deg).get("converge_pos_m", converge_pos_m);
  n.get("downsample_m", downsample_m).get("max_points", max_points);
  lidar.check(range_noise_m > 0, "range_noise_m", "must be > 0");
  lidar.check(beam_noise_deg > 0, "beam_noise_deg", "must be > 0");
  n.check(max_iterations >= 1 && max_iterations <= 50, "max_iterations", "must be in 1..50");
  n.check(residual_floor_var >= 0, "residual_floor_var", "must be >= 0");
  n.check(downsample_m >= 0, "downsample_m", "must be >= 0 (0 disables downsampling)");
  n.check(max_points > 0, "max_points", "must be > 0");
}

PlaneResidual planeResidual(const NavState& x, const Vec3& p_imu, const Vec3& normal, double d) {
  PlaneResidual r;
  r.normal = normal;
  const Vec3 p_w = x.R_world_imu * p_imu + x.p_world_imu;
  r.residual = normal.dot(p_w) + d;
  r.h.head<3>() = hat(p_imu) * x.R_world_imu.transpose() * normal;
  r.h.tail<3>() = normal;
  return r;
}

Mat3 worldPointCovariance(const NavState& x, const StateCov& P, const BodyPoint& bp) {
  const Mat3& R = x.R_world_imu;
  const Mat3 Rp = R * hat(bp.p_imu);
  return R * bp.cov_imu * R.transpose() + Rp * P.block<3, 3>(sidx::kRot, sidx::kRot) * Rp.transpose() +
         P.block<3, 3>(sidx::kPos, sidx::kPos);
}

LioUpdateResult lidarUpdate(NavState& x, StateCov& P, const std::vector<BodyPoint>& points, const PlaneFinder& map,
                            const LioConfig& cfg) {
  using Mat66 = Eigen::Matrix<double, 6, 6>;
  using Vec66 = Eigen::Matrix<double, 6, 1>;
  LioUpdateResult res;
  const NavState x_prop = x;
  const StateCov P_prop = P;
  const StateCov P_prop_inv = P_prop.ldlt().solve(StateCov::Identity());
  const double conv_rot = cfg.converge_rot_deg * M_PI / 180.0;

  // The point's own noise in the world frame (residual weights), evaluated at the prior.
  std::vector<Mat3> cov_meas_world(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    cov_meas_world[i] = x_prop.R_world_imu * points[i].cov_imu * x_prop.R_world_imu.transpose();

  StateCov K_bar = StateCov::Zero();
  Mat66 HtRH = Mat66::Zero();
  int converged_count = 0;
  for (int it = 0; it < cfg.max_iterations; ++it) {
    // 1. Associate every point with its most probable plane at the current estimate.
    HtRH.setZero();
    Vec66 HtRz = Vec66::Zero();
    res.matched_normals.clear();
    res.matched_index.clear();
    double sq = 0;
    // Association gates widen with the pose uncertainty: the prior's in the first iteration, then the
    // current posterior's (K_bar), so that gates shrink as the estimate settles.
    const StateCov& P_gate = it == 0 ? P_prop : K_bar;
    for (std::size_t i = 0; i < points.size(); ++i) {
      PointWithCov pw;
      pw.p_world = x.R_world_imu * points[i].p_imu + x.p_world_imu;
      pw.cov_world = worldPointCovariance(x, P_gate, points[i]);
      VoxelMap::PlaneMatch m;
      if (!map.findBestPlane(pw, m)) continue;
      const Plane& pl = *m.plane;
      // 2. Residual, Jacobian and variance: plane uncertainty + the point's own noise (not the state's).
      const PlaneResidual r = planeResidual(x, points[i].p_imu, pl.normal, pl.d);
      const double var = pointToPlaneVariance(pl, pw.p_world, cov_meas_world[i]) + cfg.residual_floor_var;
      HtRH += r.h * r.h.transpose() / var;
      HtRz += r.h * r.residual / var;
      res.matched_normals.push_back(pl.normal);
      res.matched_index.push_back(static_cast<int>(i));
      sq += r.residual * r.residual;
    }
    res.matched = static_cast<int>(res.matched_normals.size());
    res.iterations = it + 1;
    if (res.matched == 0) {
      x = x_prop;
      P = P_prop;
      return res;
    }
    res.rms_residual_m = std::sqrt(sq / res.matched);

    // 3. Information-form IEKF step: K_bar = (H^T R^-1 H + P^-1)^-1,
    //    delta = -K_bar H^T R^-1 z + Delta - K_bar H^T R^-1 H Delta[0:6], Delta = x_prop [-] x.
    StateCov info = P_prop_inv;
    info.topLeftCorner<6, 6>() += HtRH;
    K_bar = info.ldlt().solve(StateCov::Identity());
    const StateVec Delta = x_prop.boxminus(x);
    StateVec g = StateVec::Zero();
    g.head<6>() = HtRz + HtRH * Delta.head<6>();
    const StateVec delta = Delta - K_bar * g;
    x = x.boxplus(delta);

    // 4. Convergence: two converged iterations (or the last allowed one) end the loop.
    const bool small = delta.segment<3>(sidx::kRot).norm() < conv_rot &&
                       delta.segment<3>(sidx::kPos).norm() < cfg.converge_pos_m;
    if (small) ++converged_count;
    if (converged_count >= 2 || (small && it == cfg.max_iterations - 2)) {
      res.converged = true;
      break;
    }
  }
  // 5. Covariance update once: P = (I - K_bar H^T R^-1 H) P_prop, which equals K_bar itself
  //    (K_bar (P^-1 + H^T R^-1 H) = I), evaluated at the last linearisation point.
  P = 0.5 * (K_bar + K_bar.transpose());
  return res;
}

double degeneracySigmaMin(const std::vector<Vec3>& normals) {
  if (normals.empty()) return 0.0;
  Mat3 M = Mat3::Zero();
  for (const auto& n : normals) M += n * n.transpose();
  const Vec3 lambda = Eigen::SelfAdjointEigenSolver<Mat3>(M, Eigen::EigenvaluesOnly).eigenvalues();
  // Unit normals: trace(M) = N, so lambda_min / N is the share of the weakest direction.
  return std::sqrt(std::max(0.0, lambda.minCoeff()) / double(normals.size()));
}

}  // namespace livo
