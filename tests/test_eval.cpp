// libs/eval and livo-eval: TUM I/O and its errors, association against a brute-force oracle, Umeyama
// against known transforms, and end-to-end oracles: a ground-truth trajectory (real EuRoC Vicon data
// when ../shared/data is present, a synthetic one always) moved by a known SE(3) / Sim(3) and perturbed
// by Gaussian noise of known sigma must give back the transform, ATE RMSE = sigma sqrt(3) and
// RPE RMSE = sigma sqrt(6) (difference of two independent noises).
// livo-test-bins: livo-eval
#include "livo/common/config.hpp"
#include "livo/eval/evaluate.hpp"
#include "livo/eval/report.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace livo;
namespace fs = std::filesystem;

namespace {

constexpr double kDeg = M_PI / 180.0;
const std::string kEurocGt = std::string(LIVO_SHARED_DATA) + "/euroc_v1_01_micro/groundtruth_V1_01_easy_tum.txt";

// A fresh directory per test process for temporary files, removed at exit.
struct TempDir {
  fs::path path = fs::temp_directory_path() / ("livo_test_eval_" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};
fs::path tempDir() {
  static const TempDir dir;
  return dir.path;
}

std::string writeText(const std::string& name, const std::string& text) {
  const fs::path p = tempDir() / name;
  std::ofstream(p) << text;
  return p.string();
}

std::string writeTrajectory(const std::string& name, const Trajectory& traj) {
  const fs::path p = tempDir() / name;
  TumWriter writer(p.string());
  for (const StampedPose& s : traj) writer.write(s);
  return p.string();
}

// Message of the std::exception thrown by f ("" when nothing is thrown).
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// 120 s at 20 Hz: a Lissajous loop with height changes; yaw follows the direction of travel, roll
// and pitch oscillate.
Trajectory syntheticTrajectory() {
  Trajectory traj;
  for (int k = 0; k < 2400; ++k) {
    const double t = 1000.0 + 0.05 * k;
    const double w = 2 * M_PI / 60.0;
    const Vec3 p(6 * std::cos(w * t), 4 * std::sin(2 * w * t), 1.5 + 0.5 * std::sin(0.3 * t));
    const Vec3 v(-6 * w * std::sin(w * t), 8 * w * std::cos(2 * w * t), 0.15 * std::cos(0.3 * t));
    StampedPose s;
    s.t = t;
    s.T_world_body.linear() = expSO3(Vec3(0, 0, std::atan2(v.y(), v.x()))) *
                              expSO3(Vec3(0, 0.1 * std::sin(0.5 * t), 0)) *
                              expSO3(Vec3(0.2 * std::sin(0.7 * t), 0, 0));
    s.T_world_body.translation() = p;
    traj.push_back(s);
  }
  return traj;
}

struct Perturbation {
  Sim3 T_est_gt;              // applied to the (noisy) ground truth to make the estimate
  double sigma_pos_m = 0;     // per-axis position noise, added in the ground-truth frame
  double sigma_rot_rad = 0;   // per-axis rotation noise, right-multiplied on the body orientation
  unsigned seed = 1;
};

Trajectory perturb(const Trajectory& gt, const Perturbation& p) {
  std::mt19937 rng(p.seed);
  std::normal_distribution<double> n(0.0, 1.0);
  Trajectory est = gt;
  for (StampedPose& s : est) {
    Pose noisy = s.T_world_body;
    noisy.translation() += p.sigma_pos_m * Vec3(n(rng), n(rng), n(rng));
    noisy.linear() = noisy.linear() * expSO3(p.sigma_rot_rad * Vec3(n(rng), n(rng), n(rng)));
    s.T_world_body = p.T_est_gt.apply(noisy);
  }
  return est;
}

Sim3 knownTransform(double scale) {
  Sim3 T;
  T.R = expSO3(Vec3(0.3, -0.8, 2.1));
  T.t = Vec3(12.5, -3.0, 0.7);
  T.s = scale;
  return T;
}

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

// Brute force: every estimated pose against every ground-truth pose; nearest (last on ties), then
// one-to-one (closest, first on ties).
std::vector<PosePair> bruteForceAssociate(const Trajectory& gt, const Trajectory& est, double max_dt,
                                          double offset) {
  std::vector<PosePair> candidates;
  std::vector<double> dts;
  for (std::size_t e = 0; e < est.size(); ++e) {
    std::size_t best = 0;
    for (std::size_t g = 0; g < gt.size(); ++g)
      if (std::abs(gt[g].t - (est[e].t + offset)) <= std::abs(gt[best].t - (est[e].t + offset))) best = g;
    const double dt = std::abs(gt[best].t - (est[e].t + offset));
    if (dt <= max_dt) {
      candidates.push_back({best, e});
      dts.push_back(dt);
    }
  }
  std::vector<PosePair> out;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    bool keep = true;
    for (std::size_t m = 0; m < candidates.size(); ++m) {
      if (m == k || candidates[m].gt_index != candidates[k].gt_index) continue;
      if (dts[m] < dts[k] || (dts[m] == dts[k] && m < k)) keep = false;
    }
    if (keep) out.push_back(candidates[k]);
  }
  return out;
}

Trajectory timesOnly(const std::vector<double>& times) {
  Trajectory traj;
  for (double t : times) traj.push_back({t, Pose::Identity()});
  return traj;
}

}  // namespace

// ---------------------------------------------------------------- TUM files

TEST(TumIo, WriterFlushesEveryLineAndRoundTripsFullPrecision) {
  const Trajectory traj = perturb(syntheticTrajectory(), {knownTransform(1.0), 0.1, 0.1, 3});
  const std::string path = (tempDir() / "roundtrip.tum").string();
  TumWriter writer(path);
  for (int k = 0; k < 3; ++k) writer.write(traj[k]);
  // Still open: every written line must already be on disk.
  const Trajectory partial = readTum(path);
  ASSERT_EQ(partial.size(), 3u);
  for (std::size_t k = 3; k < traj.size(); ++k) writer.write(traj[k]);
  EXPECT_EQ(writer.count(), traj.size());

  const Trajectory back = readTum(path);
  ASSERT_EQ(back.size(), traj.size());
  for (std::size_t k = 0; k < traj.size(); ++k) {
    EXPECT_NEAR(back[k].t, traj[k].t, 1e-9 + 1e-15 * traj[k].t);
    EXPECT_LT((back[k].T_world_body.translation() - traj[k].T_world_body.translation()).norm(), 2e-9);
    EXPECT_LT(rotationAngle(back[k].T_world_body.linear().transpose() * traj[k].T_world_body.linear()), 1e-8);
  }
}

TEST(TumIo, SkipsCommentsBlankLinesAndCarriageReturns) {
  const std::string path = writeText("comments.tum",
                                     "# t x y z qx qy qz qw\n\n  \n"
                                     "1.0 1 2 3 0 0 0 1\r\n"
                                     "   # indented comment\n"
                                     "1.5\t4 5 6 0 0 0.7071068 0.7071068\n");
  const Trajectory traj = readTum(path);
  ASSERT_EQ(traj.size(), 2u);
  EXPECT_DOUBLE_EQ(traj[1].t, 1.5);
  EXPECT_TRUE(traj[1].T_world_body.translation().isApprox(Vec3(4, 5, 6)));
  EXPECT_NEAR(rotationAngle(traj[1].T_world_body.linear()), M_PI / 2, 1e-6);
}

TEST(TumIo, EmptyOrMissingFileIsAnErrorNamingTheFile) {
  for (const std::string text : {"", "# only a header\n\n"}) {
    const std::string path = writeText("empty.tum", text);
    const std::string msg = errorOf([&] { readTum(path); });
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("no poses"), std::string::npos) << msg;
  }
  const std::string missing = (tempDir() / "does_not_exist.tum").string();
  const std::string msg = errorOf([&] { readTum(missing); });
  EXPECT_NE(msg.find(missing + ": cannot open"), std::string::npos) << msg;
}

TEST(TumIo, TimesMustStrictlyIncreaseAndTheErrorNamesTheLine) {
  const std::string header = "# header\n1.0 0 0 0 0 0 0 1\n";
  for (const std::string bad : {"0.5 0 0 0 0 0 0 1\n", "1.0 0 0 0 0 0 0 1\n"}) {
    const std::string path = writeText("unsorted.tum", header + bad);
    const std::string msg = errorOf([&] { readTum(path); });
    EXPECT_NE(msg.find(path + ":3:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("strictly increasing"), std::string::npos) << msg;
  }
}

TEST(TumIo, MalformedRowsNameTheLineAndTheColumn) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"2.0 0 0 0 0 0 1\n", "got 7"},
      {"2.0 0 0 0 0 0 0 1 9\n", "got more"},
      {"2.0 0 0 0 abc 0 0 1\n", "column 'qx': not a number: 'abc'"},
      {"2.0 0 1.5x 0 0 0 0 1\n", "column 'y': not a number"},
      {"2.0 0 0 nan 0 0 0 1\n", "column 'z': value is not finite"},
      {"2.0 0 0 0 0 0 0 2\n", "quaternion norm"},
      {"2.0 0 0 0 0 0 0 0\n", "quaternion norm"},
  };
  for (const auto& [row, expected] : cases) {
    const std::string path = writeText("malformed.tum", "1.0 0 0 0 0 0 0 1\n" + row);
    const std::string msg = errorOf([&] { readTum(path); });
    EXPECT_NE(msg.find(path + ":2:"), std::string::npos) << row << " -> " << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << row << " -> " << msg;
  }
}

// ---------------------------------------------------------------- association

TEST(Associate, MatchesBruteForceOnRandomTimes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 30; ++trial) {
    // Ground truth ~20 Hz with jitter; estimate at a random rate with random gaps and a random shift.
    std::vector<double> tg, te;
    for (double t = 0; t < 20; t += 0.03 + 0.04 * u(rng)) tg.push_back(t);
    const double step = 0.005 + 0.1 * u(rng);
    for (double t = -2 + 4 * u(rng); t < 22; t += step * (0.5 + u(rng)))
      if (u(rng) > 0.2) te.push_back(t);
    const double max_dt = 0.002 + 0.03 * u(rng);
    const double offset = 0.05 * (u(rng) - 0.5);
    const auto fast = associate(timesOnly(tg), timesOnly(te), max_dt, offset);
    const auto slow = bruteForceAssociate(timesOnly(tg), timesOnly(te), max_dt, offset);
    ASSERT_EQ(fast.size(), slow.size()) << "trial " << trial;
    for (std::size_t k = 0; k < fast.size(); ++k) {
      EXPECT_EQ(fast[k].gt_index, slow[k].gt_index) << "trial " << trial << " pair " << k;
      EXPECT_EQ(fast[k].est_index, slow[k].est_index) << "trial " << trial << " pair " << k;
    }
  }
}

TEST(Associate, MaxDtAndTimeOffset) {
  std::vector<double> tg, te_close, te_far;
  for (int k = 0; k < 100; ++k) {
    tg.push_back(10.0 + 0.05 * k);
    te_close.push_back(10.0 + 0.05 * k + 0.008);
    te_far.push_back(10.0 + 0.05 * k + 0.023);  // 23 ms after one gt pose, 27 ms before the next
  }
  EXPECT_EQ(associate(timesOnly(tg), timesOnly(te_close), 0.01).size(), 100u);
  EXPECT_EQ(associate(timesOnly(tg), timesOnly(te_close), 0.005).size(), 0u);
  EXPECT_EQ(associate(timesOnly(tg), timesOnly(te_far), 0.01).size(), 0u);
  const auto shifted = associate(timesOnly(tg), timesOnly(te_far), 0.01, -0.023);
  ASSERT_EQ(shifted.size(), 100u);
  for (std::size_t k = 0; k < shifted.size(); ++k) EXPECT_EQ(shifted[k].gt_index, shifted[k].est_index);
}

TEST(Associate, FasterEstimateIsMatchedOneToOne) {
  std::vector<double> tg, te;
  for (int k = 0; k < 50; ++k) tg.push_back(0.05 * k);
  for (int k = 0; k < 250; ++k) te.push_back(0.01 * k + 0.001);  // 100 Hz, every 5th within 1 ms
  const auto pairs = associate(timesOnly(tg), timesOnly(te), 0.01);
  ASSERT_EQ(pairs.size(), 50u);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    EXPECT_EQ(pairs[k].gt_index, k);
    EXPECT_EQ(pairs[k].est_index, 5 * k);
  }
}

// ---------------------------------------------------------------- Umeyama and metrics

TEST(Umeyama, RecoversExactTransformsAndNeverReflects) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 3.0);
  std::vector<Vec3> src;
  for (int i = 0; i < 20; ++i) src.push_back(Vec3(n(rng), n(rng), n(rng)));
  for (bool with_scale : {false, true}) {
    const Sim3 A = knownTransform(with_scale ? 0.37 : 1.0);
    std::vector<Vec3> dst;
    for (const Vec3& p : src) dst.push_back(A.apply(p));
    const Sim3 B = umeyama(src, dst, with_scale);
    EXPECT_LT((B.R - A.R).norm(), 1e-9);
    EXPECT_LT((B.t - A.t).norm(), 1e-9);
    EXPECT_NEAR(B.s, A.s, 1e-9);
  }
  // A mirrored copy has no rotation that fits; the result must still be a rotation.
  std::vector<Vec3> mirrored;
  for (const Vec3& p : src) mirrored.push_back(Vec3(p.x(), p.y(), -p.z()));
  const Sim3 M = umeyama(src, mirrored, true);
  EXPECT_NEAR(M.R.determinant(), 1.0, 1e-9);
  EXPECT_GT(M.s, 0.0);
  EXPECT_NE(errorOf([&] { umeyama({Vec3::Zero(), Vec3::Ones()}, {Vec3::Zero(), Vec3::Ones()}, false); }), "");
  EXPECT_NE(errorOf([&] { umeyama(std::vector<Vec3>(4, Vec3::Ones()), std::vector<Vec3>(4, Vec3::Zero()), true); }),
            "");
}

TEST(Metrics, ErrorStatsAndDefaultDeltas) {
  const ErrorStats s = errorStats({3.0, 4.0, 0.0, 1.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(26.0 / 4.0));
  EXPECT_DOUBLE_EQ(s.median, 2.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(s.min, 0.0);
  EXPECT_EQ(defaultRpeDeltas(58.35), (std::vector<double>{5.0, 10.0, 20.0}));
  EXPECT_EQ(defaultRpeDeltas(3.0), (std::vector<double>{0.2, 0.5, 1.0}));
  EXPECT_TRUE(defaultRpeDeltas(0.0).empty());
  EXPECT_DOUBLE_EQ(pathLength({Vec3(0, 0, 0), Vec3(3, 4, 0), Vec3(3, 4, 2)}), 7.0);
}

// ---------------------------------------------------------------- end-to-end oracles

TEST(EvalOracle, SyntheticSe3) { checkOracle(syntheticTrajectory(), false); }
TEST(EvalOracle, SyntheticSim3) { checkOracle(syntheticTrajectory(), true); }
TEST(EvalOracle, SyntheticRotationNoise) { checkRotationOracle(syntheticTrajectory()); }

TEST(EvalOracle, EurocSe3) {
  if (!haveEuroc()) GTEST_SKIP() << "EuRoC ground truth not found at " << kEurocGt;
  checkOracle(readTum(kEurocGt), false);
}
TEST(EvalOracle, EurocSim3) {
  if (!haveEuroc()) GTEST_SKIP() << "EuRoC ground truth not found at " << kEurocGt;
  checkOracle(readTum(kEurocGt), true);
}
TEST(EvalOracle, EurocRotationNoise) {
  if (!haveEuroc()) GTEST_SKIP() << "EuRoC ground truth not found at " << kEurocGt;
  checkRotationOracle(readTum(kEurocGt));
}

TEST(Evaluate, TimeOffsetAndClearErrors) {
  const Trajectory gt = syntheticTrajectory();
  Trajectory late = gt;
  for (StampedPose& s : late) s.t += 0.023;
  const std::string msg = errorOf([&] { evaluate(gt, late, EvalConfig()); });
  EXPECT_NE(msg.find("no overlap"), std::string::npos) << msg;
  EXPECT_NE(msg.find("ground truth spans"), std::string::npos) << msg;

  EvalConfig shifted;
  shifted.est_time_offset_s = -0.023;
  const EvalResult r = evaluate(gt, late, shifted);
  EXPECT_EQ(r.matched, gt.size());
  EXPECT_LT(r.ate.translation_m.max, 1e-9);
  EXPECT_LT(r.mean_abs_dt_s, 1e-9);

  const Trajectory two(gt.begin(), gt.begin() + 2);
  EXPECT_NE(errorOf([&] { evaluate(gt, two, EvalConfig()); }).find("too few matched poses"), std::string::npos);
  EvalConfig bad;
  bad.max_dt_s = -1;
  EXPECT_NE(errorOf([&] { evaluate(gt, gt, bad); }).find("max_dt_s"), std::string::npos);
}

TEST(Evaluate, ConfigLoadsKeysAndRejectsBadValues) {
  const ConfigFile file = ConfigFile::parse(
      "eval: {max_dt_s: 0.02, est_time_offset_s: -0.5, with_scale: true, rpe_deltas_m: [1, 4]}\n", "eval.yaml");
  EvalConfig config;
  config.load(file.root().section("eval"));
  EXPECT_DOUBLE_EQ(config.max_dt_s, 0.02);
  EXPECT_DOUBLE_EQ(config.est_time_offset_s, -0.5);
  EXPECT_TRUE(config.with_scale);
  EXPECT_EQ(config.rpe_deltas_m, (std::vector<double>{1.0, 4.0}));
  EXPECT_NO_THROW(file.checkAllKeysUsed());
  const ConfigFile bad = ConfigFile::parse("eval: {rpe_deltas_m: [1, -2]}\n", "bad.yaml");
  const std::string msg = errorOf([&] { EvalConfig().load(bad.root().section("eval")); });
  EXPECT_NE(msg.find("bad.yaml: eval.rpe_deltas_m"), std::string::npos) << msg;
}

// ---------------------------------------------------------------- the livo-eval binary

namespace {

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

RunResult runEval(const std::string& args) {
  const fs::path out = tempDir() / "stdout.txt", err = tempDir() / "stderr.txt";
  const std::string cmd = std::string(LIVO_BINARY_DIR) + "/bin/livo-eval " + args + " >" + out.string() +
                          " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::stringstream so, se;
  so << std::ifstream(out).rdbuf();
  se << std::ifstream(err).rdbuf();
  r.out = so.str();
  r.err = se.str();
  return r;
}

bool haveBinary() { return fs::exists(std::string(LIVO_BINARY_DIR) + "/bin/livo-eval"); }

// Minimal JSON syntax check (objects, arrays, strings without escapes, numbers, literals).
bool skipJsonValue(const std::string& s, std::size_t& i) {
  auto ws = [&] { while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i; };
  ws();
  if (i >= s.size()) return false;
  if (s[i] == '{' || s[i] == '[') {
    const char close = s[i] == '{' ? '}' : ']';
    const bool object = s[i] == '{';
    ++i;
    ws();
    if (i < s.size() && s[i] == close) return ++i, true;
    while (true) {
      if (object) {
        ws();
        if (!skipJsonValue(s, i)) return false;  // key (a string)
        ws();
        if (i >= s.size() || s[i++] != ':') return false;
      }
      if (!skipJsonValue(s, i)) return false;
      ws();
      if (i < s.size() && s[i] == ',') { ++i; continue; }
      return i < s.size() && s[i++] == close;
    }
  }
  if (s[i] == '"') {
    const std::size_t end = s.find('"', i + 1);
    if (end == std::string::npos) return false;
    i = end + 1;
    return true;
  }
  for (const char* lit : {"true", "false", "null"})
    if (s.compare(i, std::strlen(lit), lit) == 0) return i += std::strlen(lit), true;
  char* end = nullptr;
  std::strtod(s.c_str() + i, &end);
  if (end == s.c_str() + i) return false;
  i = end - s.c_str();
  return true;
}

double jsonNumber(const std::string& json, const std::string& key) {
  const std::size_t k = json.find("\"" + key + "\":");
  if (k == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + k + key.size() + 3, nullptr);
}

}  // namespace

TEST(LivoEvalBinary, JsonMatchesTheLibraryAndTheOracle) {
  if (!haveBinary()) GTEST_SKIP() << "build the livo-eval target first (" << LIVO_BINARY_DIR << "/bin)";
  const Trajectory gt = syntheticTrajectory();
  const double sigma = 0.03;
  const std::string gt_path = writeTrajectory("e2e_gt.tum", gt);
  for (bool with_scale : {false, true}) {
    const Trajectory est = perturb(gt, {knownTransform(with_scale ? 0.5 : 1.0), sigma, 0.0, 9});
    const std::string est_path = writeTrajectory("e2e_est.tum", est);
    const RunResult run =
        runEval("--gt " + gt_path + " --est " + est_path + " --json" + (with_scale ? " --scale" : ""));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const std::string& json = run.out;
    std::size_t i = 0;
    ASSERT_TRUE(skipJsonValue(json, i)) << json;
    EXPECT_EQ(json.substr(i), "\n") << "one JSON object on one line";
    EXPECT_EQ(json.front(), '{');

    EvalConfig config;
    config.with_scale = with_scale;
    const EvalResult lib = evaluate(readTum(gt_path), readTum(est_path), config);
    EXPECT_NEAR(jsonNumber(json, "ate_rmse_m"), lib.ate.translation_m.rmse, 1e-8);
    EXPECT_NEAR(jsonNumber(json, "ate_mean_m"), lib.ate.translation_m.mean, 1e-8);
    EXPECT_NEAR(jsonNumber(json, "ate_median_m"), lib.ate.translation_m.median, 1e-8);
    EXPECT_NEAR(jsonNumber(json, "ate_max_m"), lib.ate.translation_m.max, 1e-8);
    EXPECT_NEAR(jsonNumber(json, "path_length_m"), lib.path_length_m, 1e-6);
    EXPECT_EQ(jsonNumber(json, "matched"), double(gt.size()));
    EXPECT_NEAR(jsonNumber(json, "ate_rmse_m"), sigma * std::sqrt(3.0), 0.05 * sigma * std::sqrt(3.0));
    EXPECT_NEAR(jsonNumber(json, "scale"), with_scale ? 2.0 : 1.0, 2e-3);
    EXPECT_NE(json.find("\"rpe\": [{\"delta_m\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"T_gt_est\": ["), std::string::npos) << json;
  }
}

TEST(LivoEvalBinary, OptionsAndErrorsGiveExitCodesAndMessages) {
  if (!haveBinary()) GTEST_SKIP() << "build the livo-eval target first (" << LIVO_BINARY_DIR << "/bin)";
  const Trajectory gt = syntheticTrajectory();
  const std::string gt_path = writeTrajectory("cli_gt.tum", gt);

  RunResult r = runEval("--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("--max-dt"), std::string::npos);

  // Text report with explicit RPE distances and a time offset.
  Trajectory late = gt;
  for (StampedPose& s : late) s.t += 0.023;
  const std::string late_path = writeTrajectory("cli_late.tum", late);
  r = runEval("--gt " + gt_path + " --est " + late_path + " --offset -0.023 --rpe-delta 2 --rpe-delta 7.5");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("matched      2400 of 2400"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("RPE       2 m"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("RPE     7.5 m"), std::string::npos) << r.out;

  r = runEval("--gt " + gt_path + " --est " + late_path);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no overlap"), std::string::npos) << r.err;
  r = runEval("--gt " + gt_path + " --est " + late_path + " --max-dt 0.03 --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(jsonNumber(r.out, "matched"), 2400.0);

  const std::string empty_path = writeText("cli_empty.tum", "");
  r = runEval("--gt " + gt_path + " --est " + empty_path + " --json");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(empty_path + ": no poses"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());

  const std::string unsorted_path = writeText("cli_unsorted.tum", "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n1.5 0 0 0 0 0 0 1\n");
  r = runEval("--gt " + unsorted_path + " --est " + gt_path);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(unsorted_path + ":3:"), std::string::npos) << r.err;

  const std::vector<std::string> usage_errors = {"--est " + gt_path,
                                                 "--gt " + gt_path + " --est " + gt_path + " --max-dt x",
                                                 "--gt " + gt_path + " --est " + gt_path + " --rpe-delta 0",
                                                 "--bogus"};
  for (const std::string& args : usage_errors) {
    r = runEval(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.err.find("livo-eval: "), std::string::npos) << args << ": " << r.err;
  }
}
