#include "livo/estimation/lio_update.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>

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

WorldPointCovariance::WorldPointCovariance(const NavState& x, const StateCov& P)
    : R_(x.R_world_imu),
      S_(x.R_world_imu * P.block<3, 3>(sidx::kRot, sidx::kRot) * x.R_world_imu.transpose()),
      P_pp_(P.block<3, 3>(sidx::kPos, sidx::kPos)) {}

Mat3 worldPointCovariance(const NavState& x, const StateCov& P, const BodyPoint& bp) {
  return WorldPointCovariance(x, P)(bp, x.R_world_imu * bp.p_imu);
}

namespace {

using Mat66 = Eigen::Matrix<double, 6, 6>;
using Vec66 = Eigen::Matrix<double, 6, 1>;

/// Points per block of the association loop: fixed, so that the partial sums (and hence the update)
/// are the same for every thread count.
constexpr std::size_t kAssociationBlock = 256;

/// One point's association at the current estimate.
struct PointMatch {
  bool matched = false;
  Vec3 normal = Vec3::Zero();
};

/// One block's share of the normal equations.
struct BlockSums {
  Mat66 HtRH = Mat66::Zero();
  Vec66 HtRz = Vec66::Zero();
  double sq = 0.0;
  double chi2 = 0.0;  ///< sum of z^2 / var
  int covered = 0;    ///< points whose root voxel holds a plane
};

/// Step 1 and 2 for points [begin, end): associate each with its most probable plane at `x` and add
/// its residual row (plane uncertainty + the point's own noise, not the state's) to `sums`.
void associateBlock(const NavState& x, const StateCov& P_gate, const std::vector<BodyPoint>& points,
                    const std::vector<Mat3>& cov_meas_world, const PlaneFinder& map, const LioConfig& cfg,
                    std::size_t begin, std::size_t end, std::vector<CachedAssociation>& assoc,
                    std::vector<PointMatch>& matches, BlockSums& out) {
  BlockSums sums;  // local, stored once at the end: no cache line shared with a neighbour block meanwhile
  const WorldPointCovariance point_cov(x, P_gate);
  for (std::size_t i = begin; i < end; ++i) {
    PointMatch& pm = matches[i];
    pm.matched = false;
    PointWithCov pw;
    const Vec3 q = x.R_world_imu * points[i].p_imu;
    pw.p_world = q + x.p_world_imu;
    pw.cov_world = point_cov(points[i], q);
    PlaneMatch m;
    const bool found = assoc[i].find(map, pw, m);
    sums.covered += assoc[i].covered();
    if (!found) continue;
    const Plane& pl = *m.plane;
    const PlaneResidual r = planeResidual(x, points[i].p_imu, pl.normal, pl.d);
    const double var = pointToPlaneVariance(pl, pw.p_world, cov_meas_world[i]) + cfg.residual_floor_var;
    sums.HtRH.noalias() += r.h * r.h.transpose() / var;
    sums.HtRz += r.h * r.residual / var;
    sums.sq += r.residual * r.residual;
    sums.chi2 += r.residual * r.residual / var;
    pm.matched = true;
    pm.normal = pl.normal;
  }
  out = sums;
}

/// Translation directions whose share sqrt(lambda / trace) of the matched planes' weighted normal
/// scatter (the position block of H^T R^-1 H) is below kMinShare are free: there the few matches off
/// the dominant planes mostly carry the planes' own fitting error (a map of one scan, a corridor's
/// walls), whose bias would move the position and, through the prior, the velocity.
constexpr double kMinShare = 0.1;

/// The free translation directions of one iteration: the projector onto the constrained ones and
/// whether the prior is too wide along a free one for its correlations to be trusted (below).
struct FreeDirections {
  Mat3 Pc = Mat3::Identity();  ///< projector onto the constrained translation directions
  bool lever = false;          ///< keep the correction off the free directions (filteredGain)
  bool any() const { return !Pc.isIdentity(0.0); }
};

/// The free directions of H^T R^-1 H, judged against the prior position covariance `Pp`. A free
/// direction is known only to within the directions whose share is as low, an angle of about
/// kMinShare: the prior's correlations carry information of the constrained directions into it with a
/// lever sigma_free / sigma_constrained, which a misalignment within that angle makes wrong once the
/// lever exceeds 1 / kMinShare (a start's or a long wall's wide prior along the axis: a centimetre of
/// floor information moved a corridor start 3.4 m). Below it (a few frames facing one wall mid-run,
/// the prior still round) the correlations are the IMU's and stand.
FreeDirections freeDirections(const Mat66& HtRH, const Mat3& Pp) {
  FreeDirections f;
  const Mat3 M = HtRH.bottomRightCorner<3, 3>();
  const double tr = M.trace();
  if (!(tr > 0)) return f;
  const Eigen::SelfAdjointEigenSolver<Mat3> es(M / tr);
  double var_free = 0.0, var_constrained = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const Vec3 u = es.eigenvectors().col(k);
    const double var = u.dot(Pp * u);
    if (std::sqrt(std::max(0.0, es.eigenvalues()(k))) < kMinShare) {
      f.Pc -= u * u.transpose();
      var_free = std::max(var_free, var);
    } else {
      var_constrained = std::min(var_constrained, var);
    }
  }
  f.lever = f.any() && var_free * kMinShare * kMinShare > var_constrained;
  return f;
}

using Gain = Eigen::Matrix<double, kStateDim, 6>;

/// The gain K_bar[:, 0:6]; where the free directions' lever is too long, its position and velocity
/// rows projected onto the constrained directions, so that the update neither measures nor moves them
/// along the free ones.
Gain filteredGain(const StateCov& K_bar, const FreeDirections& f) {
  Gain L = K_bar.leftCols<6>();
  if (f.lever) {
    L.middleRows<3>(sidx::kPos) = f.Pc * L.middleRows<3>(sidx::kPos);
    L.middleRows<3>(sidx::kVel) = f.Pc * L.middleRows<3>(sidx::kVel);
  }
  return L;
}

void projectTranslation(const Mat3& Pc, Mat66& HtRH, Vec66& HtRz) {
  Mat66 T = Mat66::Identity();
  T.bottomRightCorner<3, 3>() = Pc;
  HtRH = T * HtRH * T;
  HtRz = T * HtRz;
}

}  // namespace

LioUpdateResult lidarUpdate(NavState& x, StateCov& P, const std::vector<BodyPoint>& points, const PlaneFinder& map,
                            const LioConfig& cfg, WorkerPool* pool) {
  LioUpdateResult res;
  const NavState x_prop = x;
  const StateCov P_prop = P;
  const StateCov P_prop_inv = P_prop.ldlt().solve(StateCov::Identity());
  const double conv_rot = cfg.converge_rot_deg * M_PI / 180.0;

  // The point's own noise in the world frame (residual weights), evaluated at the prior.
  std::vector<Mat3> cov_meas_world(points.size());
  forRange(pool, points.size(), kAssociationBlock, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      cov_meas_world[i] = x_prop.R_world_imu * points[i].cov_imu * x_prop.R_world_imu.transpose();
  });

  std::vector<PointMatch> matches(points.size());
  // Each point's candidate planes, kept while it stays in its voxel (the map does not change here).
  std::vector<CachedAssociation> assoc(points.size());
  std::vector<BlockSums> blocks((points.size() + kAssociationBlock - 1) / kAssociationBlock);
  StateCov K_bar = StateCov::Zero();
  const Mat3 Pp_prop = P_prop.block<3, 3>(sidx::kPos, sidx::kPos);
  FreeDirections free;         // the last iteration's free translation directions
  Mat66 S = Mat66::Zero();     // and its projected H^T R^-1 H
  int converged_count = 0;
  for (int it = 0; it < cfg.max_iterations; ++it) {
    // 1. Associate every point with its most probable plane at the current estimate (blocks in
    //    parallel, summed in block order). Association gates widen with the pose uncertainty: the
    //    prior's in the first iteration, then the current posterior's (K_bar), so that gates shrink as
    //    the estimate settles.
    const StateCov& P_gate = it == 0 ? P_prop : K_bar;
    forRange(pool, points.size(), kAssociationBlock, [&](std::size_t begin, std::size_t end) {
      associateBlock(x, P_gate, points, cov_meas_world, map, cfg, begin, end, assoc, matches,
                     blocks[begin / kAssociationBlock]);
    });
    Mat66 HtRH = Mat66::Zero();
    Vec66 HtRz = Vec66::Zero();
    double sq = 0, chi2 = 0;
    int covered = 0;
    for (const BlockSums& b : blocks) {
      HtRH += b.HtRH;
      HtRz += b.HtRz;
      sq += b.sq;
      chi2 += b.chi2;
      covered += b.covered;
    }
    res.covered = covered;
    res.matched_normals.clear();
    res.matched_index.clear();
    for (std::size_t i = 0; i < points.size(); ++i)
      if (matches[i].matched) {
        res.matched_normals.push_back(matches[i].normal);
        res.matched_index.push_back(static_cast<int>(i));
      }
    res.matched = static_cast<int>(res.matched_normals.size());
    res.iterations = it + 1;
    if (res.matched == 0) {
      x = x_prop;
      P = P_prop;
      return res;
    }
    res.rms_residual_m = std::sqrt(sq / res.matched);
    res.nis = chi2 / res.matched;

    // 3. Information-form IEKF step: K_bar = (H^T R^-1 H + P^-1)^-1,
    //    delta = -K_bar H^T R^-1 z + Delta - K_bar H^T R^-1 H Delta[0:6], Delta = x_prop [-] x.
    free = freeDirections(HtRH, Pp_prop);
    if (free.any()) projectTranslation(free.Pc, HtRH, HtRz);
    S = HtRH;
    StateCov info = P_prop_inv;
    info.topLeftCorner<6, 6>() += HtRH;
    K_bar = info.ldlt().solve(StateCov::Identity());
    const StateVec Delta = x_prop.boxminus(x);
    StateVec g = StateVec::Zero();
    g.head<6>() = HtRz + HtRH * Delta.head<6>();
    const StateVec delta = Delta - filteredGain(K_bar, free) * g.head<6>();
    x = x.boxplus(delta);

    // 4. Convergence: two converged iterations, or one at the second-to-last allowed iteration, end the
    //    loop; otherwise it runs to max_iterations.
    const bool small = delta.segment<3>(sidx::kRot).norm() < conv_rot &&
                       delta.segment<3>(sidx::kPos).norm() < cfg.converge_pos_m;
    if (small) ++converged_count;
    if (converged_count >= 2 || (small && it == cfg.max_iterations - 2)) {
      res.converged = true;
      break;
    }
  }
  // 5. Covariance update once, evaluated at the last linearisation point: P = K_bar =
  //    (I - K_bar H^T R^-1 H) P_prop. Where the gain was filtered (free directions with a long lever),
  //    P is the Joseph form's for that gain L: P = (I - L S E) P_prop (I - L S E)^T + L S L^T, with
  //    S the projected H^T R^-1 H and E selecting the pose block.
  if (!free.lever) {
    P = 0.5 * (K_bar + K_bar.transpose());
  } else {
    const Gain L = filteredGain(K_bar, free);
    StateCov A = StateCov::Identity();
    A.leftCols<6>() -= L * S;
    const StateCov Pj = A * P_prop * A.transpose() + L * S * L.transpose();
    P = 0.5 * (Pj + Pj.transpose());
  }
  // The correction in the prediction's sigmas, with the LiDAR's own resolution on the pose added (a
  // covariance the many points shrink below what the map's planes are accurate to would make every
  // millimetre of plane bias an inconsistency).
  Mat66 C = P_prop.topLeftCorner<6, 6>();
  const double beam = cfg.beam_noise_deg * M_PI / 180.0;
  C.topLeftCorner<3, 3>() += beam * beam * Mat3::Identity();
  C.bottomRightCorner<3, 3>() += cfg.range_noise_m * cfg.range_noise_m * Mat3::Identity();
  const StateVec correction = x.boxminus(x_prop);
  const Vec66 pose = correction.head<6>();
  res.correction_chi2 = pose.dot(C.ldlt().solve(pose));
  res.correction_m = correction.segment<3>(sidx::kPos).norm();
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
