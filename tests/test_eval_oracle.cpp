// libs/eval end-to-end oracles: a ground-truth trajectory (real EuRoC Vicon data when ../shared/data is
// present, a synthetic one always) moved by a known SE(3) / Sim(3) and perturbed by Gaussian noise of known
// sigma must give back the transform, ATE RMSE = sigma sqrt(3) and RPE RMSE = sigma sqrt(6) (difference of
// two independent noises).
#include "eval_test_util.hpp"

#include "livo/eval/evaluate.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

using namespace livo;
using namespace livo::test;
namespace fs = std::filesystem;

namespace {

constexpr double kDeg = M_PI / 180.0;
const std::string kEurocGt = std::string(LIVO_SHARED_DATA) + "/euroc_v1_01_micro/groundtruth_V1_01_easy_tum.txt";

// The oracle check shared by the real and the synthetic base trajectory.
void checkOracle(const Trajectory& gt, bool with_scale) {
  const double sigma = 0.05;
  Perturbation pert;
  pert.T_est_gt = knownTransform(with_scale ? 2.5 : 1.0);
  pert.sigma_pos_m = sigma;
  const Trajectory est = perturb(gt, pert);
  EvalConfig config;
  config.with_scale = with_scale;
  const EvalResult r = evaluate(gt, est, config);

  ASSERT_EQ(r.matched, gt.size());
  // The alignment must undo the applied transform: Delta = T_gt_est o A is the identity up to the
  // estimation error x = [dtheta, dt, ds] of a least-squares fit, whose covariance is
  // sigma^2 (J^T J)^-1 with J_i = [-[p_i]x, I, p_i] (linearised Delta(p) = (1+ds) Exp(dtheta) p + dt).
  // So x^T J^T J x / sigma^2 follows a chi-square law with 6 (7 with scale) degrees of freedom.
  const Sim3& A = pert.T_est_gt;
  const Mat3 R_delta = r.T_gt_est.R * A.R;
  const Vec3 t_delta = r.T_gt_est.s * r.T_gt_est.R * A.t + r.T_gt_est.t;
  Eigen::Matrix<double, 7, 1> x;
  x << logSO3(R_delta), t_delta, r.T_gt_est.s * A.s - 1.0;
  Eigen::Matrix<double, 7, 7> JtJ = Eigen::Matrix<double, 7, 7>::Zero();
  for (const StampedPose& s : gt) {
    Eigen::Matrix<double, 3, 7> J;
    const Vec3 p = s.T_world_body.translation();
    J << -hat(p), Mat3::Identity(), p;
    JtJ += J.transpose() * J;
  }
  // With noise on the source points Umeyama's scale is biased low (errors in variables): E[s_delta]
  // = var_p / (var_p + 3 sigma^2), var_p = mean |p - p_mean|^2; the means still match, so the bias
  // moves dt by -ds p_mean. Rotation and translation alone (SE(3)) are unbiased.
  if (with_scale) {
    Vec3 p_mean = Vec3::Zero();
    for (const StampedPose& s : gt) p_mean += s.T_world_body.translation() / double(gt.size());
    double var_p = 0;
    for (const StampedPose& s : gt) var_p += (s.T_world_body.translation() - p_mean).squaredNorm() / double(gt.size());
    const double ds_bias = -3 * sigma * sigma / (var_p + 3 * sigma * sigma);
    x.segment<3>(3) -= -ds_bias * p_mean;
    x(6) -= ds_bias;
  }
  const int dof = with_scale ? 7 : 6;
  const double mahalanobis_sq = x.head(dof).dot(JtJ.topLeftCorner(dof, dof) * x.head(dof)) / (sigma * sigma);
  EXPECT_LT(mahalanobis_sq, 40.0) << "chi-square(" << dof << ") value, P(> 40) < 1e-6";
  EXPECT_LT(rotationAngle(R_delta), 0.5 * kDeg);  // coarse bounds, for readable failures
  EXPECT_LT(t_delta.norm(), 0.05);
  EXPECT_NEAR(r.T_gt_est.s, 1.0 / A.s, with_scale ? 0.01 / A.s : 0.0);
  // ATE: E|n|^2 = 3 sigma^2; fitting 6-7 parameters to thousands of pairs changes it by < 0.2 %.
  EXPECT_NEAR(r.ate.translation_m.rmse, sigma * std::sqrt(3.0), 0.05 * sigma * std::sqrt(3.0));
  // Rotations were not perturbed: every rotation error is the alignment's, angle(R_gt^T R_delta R_gt).
  EXPECT_NEAR(r.ate.rotation_deg.rmse, rotationAngle(R_delta) / kDeg, 1e-9);
  EXPECT_NEAR(r.ate.rotation_deg.max, rotationAngle(R_delta) / kDeg, 1e-9);
  // RPE: E = (n_j - n_i) rotated, E|.|^2 = 6 sigma^2; rotations were not perturbed and a rigid
  // alignment cancels in relative poses.
  ASSERT_FALSE(r.rpe.empty());
  for (const RpeResult& e : r.rpe) {
    ASSERT_GT(e.translation_m.count, 100u) << "delta " << e.delta_m;
    EXPECT_NEAR(e.translation_m.rmse, sigma * std::sqrt(6.0), 0.08 * sigma * std::sqrt(6.0)) << e.delta_m;
    EXPECT_LT(e.rotation_deg.max, 1e-6) << e.delta_m;
  }
}

// Rotation noise only: ATE rotation RMSE = sigma_r sqrt(3), RPE rotation RMSE = sigma_r sqrt(6),
// positions exact so the ATE translation vanishes.
void checkRotationOracle(const Trajectory& gt) {
  const double sigma_r = 0.5 * kDeg;
  Perturbation pert;
  pert.T_est_gt = knownTransform(1.0);
  pert.sigma_rot_rad = sigma_r;
  pert.seed = 5;
  const EvalResult r = evaluate(gt, perturb(gt, pert), EvalConfig());
  EXPECT_LT(r.ate.translation_m.max, 1e-6);
  const double expect_ate_deg = sigma_r * std::sqrt(3.0) / kDeg;
  EXPECT_NEAR(r.ate.rotation_deg.rmse, expect_ate_deg, 0.05 * expect_ate_deg);
  for (const RpeResult& e : r.rpe) {
    const double expect_rpe_deg = sigma_r * std::sqrt(6.0) / kDeg;
    EXPECT_NEAR(e.rotation_deg.rmse, expect_rpe_deg, 0.08 * expect_rpe_deg) << e.delta_m;
  }
}

bool haveEuroc() { return fs::exists(kEurocGt); }

}  // namespace

// ---------------------------------------------------------------- end-to-end oracles

TEST(EvalOracle, SyntheticSe3) { checkOracle(syntheticTrajectory(), false); }
TEST(EvalOracle, SyntheticSim3) { checkOracle(syntheticTrajectory(), true); }
TEST(EvalOracle, SyntheticRotationNoise) { checkRotationOracle(syntheticTrajectory()); }

TEST(EvalOracle, EurocSe3) {
  if (!haveEuroc()) LIVO_SKIP() << "EuRoC ground truth not found at " << kEurocGt;
  checkOracle(readTum(kEurocGt), false);
}
TEST(EvalOracle, EurocSim3) {
  if (!haveEuroc()) LIVO_SKIP() << "EuRoC ground truth not found at " << kEurocGt;
  checkOracle(readTum(kEurocGt), true);
}
TEST(EvalOracle, EurocRotationNoise) {
  if (!haveEuroc()) LIVO_SKIP() << "EuRoC ground truth not found at " << kEurocGt;
  checkRotationOracle(readTum(kEurocGt));
}
