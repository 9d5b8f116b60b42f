#include "livo/loop/loop_verifier.hpp"

#include <Eigen/Eigenvalues>

#include "livo/map/point_cov.hpp"
#include "livo/map/voxel_key.hpp"
#include "livo/map/voxel_map.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace livo {

void LoopVerifyConfig::load(const ConfigNode& loop, double range_sigma, double bearing_sigma) {
  range_sigma_m = range_sigma;
  bearing_sigma_deg = bearing_sigma;
  loop.get("verify_voxel_m", voxel_m).get("verify_downsample_m", downsample_m);
  loop.get("verify_iterations", max_iterations).get("min_overlap", min_overlap).get("max_residual_m", max_rms_m);
  loop.get("max_drift_fraction", drift_fraction).get("max_drift_m", drift_base_m);
  loop.get("max_drift_yaw_deg_per_100m", drift_yaw_deg_per_100m).get("max_drift_yaw_deg", drift_yaw_base_deg);
  loop.get("min_sigma", min_sigma);
  loop.check(std::isfinite(min_sigma) && min_sigma >= 0 && min_sigma < 0.58, "min_sigma",
             "must be in [0, 0.577] (0: no degeneracy check)");
  auto positive = [&](double v, const char* key) { loop.check(std::isfinite(v) && v > 0, key, "must be > 0"); };
  positive(voxel_m, "verify_voxel_m");
  positive(downsample_m, "verify_downsample_m");
  loop.check(max_iterations >= 1 && max_iterations <= 1000, "verify_iterations", "must be in [1, 1000]");
  loop.check(std::isfinite(min_overlap) && min_overlap > 0 && min_overlap <= 1, "min_overlap", "must be in (0, 1]");
  loop.check(std::isfinite(max_rms_m) && max_rms_m >= 0, "max_residual_m", "must be >= 0 (0: from lidar.range_noise_m)");
  loop.check(std::isfinite(drift_fraction) && drift_fraction >= 0 && drift_fraction <= 1, "max_drift_fraction",
             "must be in [0, 1]");
  loop.check(std::isfinite(drift_base_m) && drift_base_m >= 0, "max_drift_m", "must be >= 0");
  loop.check(std::isfinite(drift_yaw_deg_per_100m) && drift_yaw_deg_per_100m >= 0, "max_drift_yaw_deg_per_100m",
             "must be >= 0");
  loop.check(std::isfinite(drift_yaw_base_deg) && drift_yaw_base_deg >= 0 && drift_yaw_base_deg <= 180,
             "max_drift_yaw_deg", "must be in [0, 180]");
}

double LoopVerifyConfig::maxRms() const {
  if (max_rms_m > 0) return max_rms_m;
  return 3.0 * std::sqrt(range_sigma_m * range_sigma_m + VoxelMapConfig{}.min_eigen_value);
}

const char* toString(LoopReject r) {
  switch (r) {
    case LoopReject::None: return "accepted";
    case LoopReject::TooFewPoints: return "too few points";
    case LoopReject::NoConvergence: return "registration did not converge";
    case LoopReject::LowOverlap: return "low overlap";
    case LoopReject::HighResidual: return "high residual";
    case LoopReject::Degenerate: return "degenerate (the planes leave a direction free)";
    case LoopReject::Inconsistent: return "inconsistent with the odometry";
  }
  return "?";
}

std::vector<Vec3> thinPoints(const std::vector<Vec3>& points, double voxel_m) {
  std::unordered_set<VoxelKey, VoxelKeyHash> seen;
  std::vector<Vec3> out;
  for (const Vec3& p : points)
    if (p.allFinite() && seen.insert(VoxelKey::fromPoint(p, voxel_m)).second) out.push_back(p);
  return out;
}

namespace {

struct Step {
  int matched = 0;
  double sq_sum = 0.0;  // unweighted squared distances of the matched points
  Mat3 normals = Mat3::Zero();  // sum of n n^T of the matched planes
};

// One association + Gauss-Newton step of T (right perturbation: R Exp(dθ), t + dt); with `solve` false
// only the association is scored.
// `inflate_var` (m^2) is added to every point's covariance: it widens the association gates while the
// pose is still metres off.
Step gaussNewton(const VoxelMap& planes, const std::vector<Vec3>& pts, const std::vector<Mat3>& covs, Pose& T,
                 double inflate_var, bool solve, Eigen::Matrix<double, 6, 1>* delta) {
  Step s;
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
  const Mat3 R = T.linear();
  for (std::size_t i = 0; i < pts.size(); ++i) {
    PointWithCov pw;
    pw.p_world = T * pts[i];
    pw.cov_world = R * covs[i] * R.transpose() + inflate_var * Mat3::Identity();
    PlaneMatch m;
    if (!planes.findBestPlane(pw, m)) continue;
    ++s.matched;
    s.sq_sum += m.distance * m.distance;
    const Vec3& n = m.plane->normal;
    s.normals.noalias() += n * n.transpose();
    if (!solve) continue;
    Eigen::Matrix<double, 1, 6> J;
    J.leftCols<3>() = -(n.transpose() * R * hat(pts[i]));
    J.rightCols<3>() = n.transpose();
    const double w = 1.0 / std::max(m.sigma_l, 1e-6);
    H.noalias() += w * J.transpose() * J;
    b.noalias() -= w * J.transpose() * m.distance;
  }
  if (solve && s.matched >= 6) {
    *delta = H.ldlt().solve(b);
    if (!delta->allFinite()) delta->setZero();
    T.linear() = R * expSO3(delta->head<3>());
    T.translation() += delta->tail<3>();
  } else if (delta) {
    delta->setZero();
  }
  return s;
}

}  // namespace

LoopCheck LoopVerifier::finish(LoopCheck c) {
  switch (c.reason) {
    case LoopReject::None: ++counts_.accepted; break;
    case LoopReject::TooFewPoints: ++counts_.too_few_points; break;
    case LoopReject::NoConvergence: ++counts_.no_convergence; break;
    case LoopReject::LowOverlap: ++counts_.low_overlap; break;
    case LoopReject::HighResidual: ++counts_.high_residual; break;
    case LoopReject::Degenerate: ++counts_.degenerate; break;
    case LoopReject::Inconsistent: ++counts_.inconsistent; break;
  }
  c.accepted = c.reason == LoopReject::None;
  return c;
}

void LoopCheckCounts::addCounters(const std::string& prefix, std::map<std::string, double>& c) const {
  c[prefix + "_checks"] = double(total());
  c[prefix + "_accepted"] = double(accepted);
  c[prefix + "_rejected_too_few_points"] = double(too_few_points);
  c[prefix + "_rejected_no_convergence"] = double(no_convergence);
  c[prefix + "_rejected_low_overlap"] = double(low_overlap);
  c[prefix + "_rejected_high_residual"] = double(high_residual);
  c[prefix + "_rejected_degenerate"] = double(degenerate);
  c[prefix + "_rejected_inconsistent"] = double(inconsistent);
}

LoopCheck LoopVerifier::verify(const std::vector<Vec3>& cand_points, const std::vector<Vec3>& query_points,
                               double yaw_guess, const Pose& T_odom, double path_between_m) {
  LoopCheck c;
  const double drift_m = cfg_.drift_base_m + cfg_.drift_fraction * path_between_m;
  if (T_odom.translation().norm() > drift_m + cfg_.max_place_offset_m) {
    // The odometry cannot have drifted that far: a look-alike elsewhere (no registration needed).
    c.odometry_gap_m = T_odom.translation().norm();
    c.reason = LoopReject::Inconsistent;
    return finish(c);
  }
  const std::vector<Vec3> query = thinPoints(query_points, cfg_.downsample_m);
  std::size_t cand_n = 0;
  for (const Vec3& p : cand_points) cand_n += p.allFinite();
  if (static_cast<int>(query.size()) < cfg_.min_points || static_cast<int>(cand_n) < cfg_.min_points)
    return finish(c);

  // The candidate's planes, coarse to fine: voxel maps of the LiDAR update built from its points alone
  // with root voxels of 4, 2 and 1 x verify_voxel_m. On the coarse maps the points' covariance is
  // inflated by (edge / 4)^2 so that a pose metres off still associates (gate 3 sigma: 3 m at 4 m
  // voxels), on the finest it is the sensor's own.
  std::vector<PointWithCov> cand;
  cand.reserve(cand_n);
  for (const Vec3& p : cand_points)
    if (p.allFinite()) cand.push_back({p, pointCovarianceBody(p, cfg_.range_sigma_m, cfg_.bearing_sigma_deg)});
  struct Level {
    VoxelMap planes;
    double inflate_var;
  };
  std::vector<Level> levels;
  for (const double scale : {4.0, 2.0, 1.0}) {
    VoxelMapConfig vcfg;
    vcfg.voxel_size_m = scale * cfg_.voxel_m;
    Level l{VoxelMap(vcfg), scale > 1.0 ? std::pow(vcfg.voxel_size_m / 4.0, 2) : 0.0};
    l.planes.insert(cand);
    levels.push_back(std::move(l));
  }
  std::vector<Mat3> covs;
  covs.reserve(query.size());
  for (const Vec3& p : query) covs.push_back(pointCovarianceBody(p, cfg_.range_sigma_m, cfg_.bearing_sigma_deg));

  // Start: the descriptor's yaw and its neighbours 2 deg apart over +-6 deg (a sector of the default
  // descriptor is 6 deg), at the odometry's translation and at none; the start with the most matches
  // on the coarsest map wins.
  Pose T = Pose::Identity();
  int best_matched = -1;
  const Vec3 starts[2] = {Vec3::Zero(), T_odom.translation()};
  for (const Vec3& t0 : starts) {
    for (int k = -3; k <= 3; ++k) {
      Pose S = Pose::Identity();
      S.linear() = Eigen::AngleAxisd(-yaw_guess + k * 2.0 * M_PI / 180.0, Vec3::UnitZ()).toRotationMatrix();
      S.translation() = t0;
      const Step st = gaussNewton(levels[0].planes, query, covs, S, levels[0].inflate_var, false, nullptr);
      if (st.matched > best_matched) {
        best_matched = st.matched;
        T = S;
      }
    }
  }

  // Gauss-Newton on each level until the step is below 1 mm and 0.01 deg; the finest must converge.
  bool converged = false;
  for (const Level& l : levels) {
    converged = false;
    for (int it = 0; it < cfg_.max_iterations; ++it) {
      ++c.iterations;
      Eigen::Matrix<double, 6, 1> d;
      const Step st = gaussNewton(l.planes, query, covs, T, l.inflate_var, true, &d);
      if (st.matched < 6) break;
      if (d.head<3>().norm() < 0.01 * M_PI / 180.0 && d.tail<3>().norm() < 1e-3) {
        converged = true;
        break;
      }
    }
  }
  const Step final_step = gaussNewton(levels.back().planes, query, covs, T, 0.0, false, nullptr);
  c.T_cand_query = T;
  c.overlap = double(final_step.matched) / double(query.size());
  c.rms_m = final_step.matched > 0 ? std::sqrt(final_step.sq_sum / final_step.matched) : 0.0;
  if (final_step.matched > 0) {
    const double lambda_min = Eigen::SelfAdjointEigenSolver<Mat3>(final_step.normals).eigenvalues()(0);
    c.sigma_min = std::sqrt(std::max(0.0, lambda_min) / final_step.matched);
  }
  const Pose gap = T_odom.inverse() * T;
  c.odometry_gap_m = (T.translation() - T_odom.translation()).norm();
  c.odometry_gap_deg = rotationAngle(gap.linear()) * 180.0 / M_PI;
  if (!converged) c.reason = LoopReject::NoConvergence;
  else if (c.overlap < cfg_.min_overlap) c.reason = LoopReject::LowOverlap;
  else if (c.rms_m > cfg_.maxRms()) c.reason = LoopReject::HighResidual;
  else if (c.sigma_min < cfg_.min_sigma) c.reason = LoopReject::Degenerate;
  else if (c.odometry_gap_m > drift_m ||
           c.odometry_gap_deg > cfg_.drift_yaw_base_deg + cfg_.drift_yaw_deg_per_100m * path_between_m / 100.0)
    c.reason = LoopReject::Inconsistent;
  else c.reason = LoopReject::None;
  return finish(c);
}

}  // namespace livo
