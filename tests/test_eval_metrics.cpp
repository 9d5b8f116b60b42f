// libs/eval: Umeyama against known transforms (never a reflection), error statistics and default deltas,
// evaluate() with a time offset, its clear errors, and its config.
#include "eval_test_util.hpp"

#include "livo/common/config.hpp"
#include "livo/eval/evaluate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace livo;
using namespace livo::test;

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

// A fixed alignment (livo-eval --align-like): the estimate is not aligned, so an error of its frame stays.
TEST(Evaluate, AFixedAlignmentKeepsTheFrameError) {
  const Trajectory gt = syntheticTrajectory();
  Pose offset = Pose::Identity();
  offset.translation() = Vec3(0.3, -0.4, 0.0);  // the estimate's frame 0.5 m off
  Trajectory est = gt;
  for (StampedPose& s : est) s.T_world_body = offset * s.T_world_body;
  EXPECT_LT(evaluate(gt, est, EvalConfig()).ate.translation_m.max, 1e-9) << "aligned away";
  EvalConfig fixed;
  fixed.fixed_alignment = Sim3{};  // identity: the frames are the same
  const EvalResult r = evaluate(gt, est, fixed);
  EXPECT_NEAR(r.ate.translation_m.mean, 0.5, 1e-9);
  EXPECT_NEAR(r.ate.translation_m.max, 0.5, 1e-9);
  // The alignment of another run in the same (offset) frame takes the offset out.
  fixed.fixed_alignment = evaluate(gt, est, EvalConfig()).T_gt_est;
  EXPECT_LT(evaluate(gt, est, fixed).ate.translation_m.max, 1e-9);
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
