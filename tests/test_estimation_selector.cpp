// The adaptive visual frame selector (livo/estimation/frame_selector.hpp): the motion thresholds of
// docs/algorithms.md, and the information trigger against brute force (a full-state Kalman update and a
// search over axes for the generalised eigenvalue).
#include "livo/common/config.hpp"
#include "livo/common/so3.hpp"
#include "livo/estimation/frame_selector.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <random>
#include <string>

using namespace livo;

namespace {

StateCov randomCov(std::mt19937& rng, double scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix<double, kStateDim, kStateDim> A;
  for (int i = 0; i < kStateDim; ++i)
    for (int j = 0; j < kStateDim; ++j) A(i, j) = n(rng);
  return scale * (A * A.transpose() / kStateDim + 0.1 * StateCov::Identity());
}

/// The posterior covariance of an update with k random rows of noise sigma (information form).
StateCov afterUpdate(std::mt19937& rng, const StateCov& P, int k, double sigma) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::MatrixXd H(k, kStateDim);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < kStateDim; ++j) H(i, j) = n(rng);
  const StateCov info = P.inverse() + H.transpose() * H / (sigma * sigma);
  const StateCov Pa = info.inverse();
  return 0.5 * (Pa + Pa.transpose());
}

/// max over unit v of v^T I v / v^T P^-1 v by sampling axes (a lower bound of the generalised eigenvalue).
double sampledRatio(std::mt19937& rng, const Mat3& I, const Mat3& P) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Mat3 Pinv = P.inverse();
  double best = 0.0;
  for (int s = 0; s < 200000; ++s) {
    const Vec3 v(n(rng), n(rng), n(rng));
    best = std::max(best, v.dot(I * v) / v.dot(Pinv * v));
  }
  return best;
}

NavState stateAt(const Vec3& p, const Mat3& R) {
  NavState x;
  x.p_world_imu = p;
  x.R_world_imu = R;
  return x;
}

SelectorConfig motionOnly() {
  SelectorConfig c;
  c.information_ratio = 0.0;
  return c;
}

}  // namespace

TEST(FrameSelector, MotionThresholdsFollowSigmaMin) {
  FrameSelector sel(motionOnly(), VisualMode::Adaptive);
  const StateCov P = 1e-4 * StateCov::Identity();
  const NavState x0 = stateAt(Vec3::Zero(), Mat3::Identity());
  EXPECT_TRUE(sel.select(x0, P, 0.3, false)) << "the first image is always used";
  sel.markUsed(x0, P, P);
  const double smin = 0.3;
  // Until the LiDAR has constrained every direction for degenerate_frames (3) frames in a row, every
  // image is used (an unproven start); then the motion thresholds decide.
  for (int i = 0; i < 3; ++i) {
    EXPECT_FALSE(sel.constrainedOnce());
    EXPECT_TRUE(sel.select(stateAt(Vec3::Zero(), Mat3::Identity()), P, smin, false)) << "frame " << i;
    EXPECT_FALSE(sel.degenerate(true, i == 1 ? 0.01 : smin)) << "frame " << i;  // a low frame restarts the run
  }
  EXPECT_FALSE(sel.degenerate(true, smin));  // the second good frame in a row
  EXPECT_FALSE(sel.constrainedOnce());
  EXPECT_TRUE(sel.select(stateAt(Vec3::Zero(), Mat3::Identity()), P, smin, false));
  EXPECT_FALSE(sel.degenerate(true, smin));  // the third
  EXPECT_TRUE(sel.constrainedOnce()) << "three frames at or above the threshold in a row";
  const double tau_t = std::sqrt(3.0) * smin * 1.0;               // indoor tau_predef 1 m
  const double tau_r = std::sqrt(3.0) * smin * 60.0 * M_PI / 180;  // and 60 deg
  EXPECT_NEAR(sel.translationThreshold(smin), tau_t, 1e-12);
  EXPECT_NEAR(sel.rotationThreshold(smin), tau_r, 1e-12);
  EXPECT_FALSE(sel.select(stateAt(Vec3(0.99 * tau_t, 0, 0), Mat3::Identity()), P, smin, false));
  EXPECT_TRUE(sel.select(stateAt(Vec3(0, 1.01 * tau_t, 0), Mat3::Identity()), P, smin, false));
  EXPECT_FALSE(sel.select(stateAt(Vec3::Zero(), expSO3(Vec3(0, 0, 0.99 * tau_r))), P, smin, false));
  EXPECT_TRUE(sel.select(stateAt(Vec3::Zero(), expSO3(Vec3(1.01 * tau_r, 0, 0))), P, smin, false));
  EXPECT_TRUE(sel.select(x0, P, smin, true)) << "degenerate LiDAR: every image";
  EXPECT_TRUE(FrameSelector(motionOnly(), VisualMode::All).select(x0, P, smin, false));
  EXPECT_FALSE(FrameSelector(motionOnly(), VisualMode::Off).select(x0, P, smin, true));
}

TEST(FrameSelector, DegeneracyNeedsConsecutiveFrames) {
  FrameSelector sel(motionOnly(), VisualMode::Adaptive);  // 0.07, 3 frames
  EXPECT_FALSE(sel.degenerate(true, 0.01));
  EXPECT_FALSE(sel.degenerate(true, 0.01));
  EXPECT_FALSE(sel.degenerate(false, 0.0)) << "a frame without matches says nothing";
  EXPECT_TRUE(sel.degenerate(true, 0.01));
  EXPECT_FALSE(sel.degenerate(true, 0.2));
}

// The information gain per marginal equals P_after^-1 - P_before^-1 of a full-state update, and the
// trigger's lambda is the generalised eigenvalue of (I, P^-1), found here by searching axes.
TEST(FrameSelector, InformationRatioMatchesBruteForce) {
  std::mt19937 rng(11);
  const StateCov Pb = randomCov(rng, 1e-4);
  const StateCov Pa = afterUpdate(rng, Pb, 40, 2e-2);
  const Mat3 R = expSO3(Vec3(0.3, -0.5, 1.1));
  const NavState x = stateAt(Vec3(1, 2, 3), R);
  const FrameSelector::PoseInfo I = poseInformationGain(x, Pb, Pa);
  const Mat3 I_rot = Pa.block<3, 3>(0, 0).inverse() - Pb.block<3, 3>(0, 0).inverse();
  const Mat3 I_pos_world = Pa.block<3, 3>(3, 3).inverse() - Pb.block<3, 3>(3, 3).inverse();
  EXPECT_LE((I.rotation - I_rot).norm(), 1e-6 * I_rot.norm());
  EXPECT_LE((I.position_body - R.transpose() * I_pos_world * R).norm(), 1e-6 * I_pos_world.norm());

  SelectorConfig cfg;
  FrameSelector sel(cfg, VisualMode::Adaptive);
  EXPECT_EQ(sel.informationRatio(x, Pb), 0.0) << "no visual update yet";
  sel.markUsed(x, Pb, Pa);
  const StateCov Pnow = randomCov(rng, 3e-4);
  const double lambda = sel.informationRatio(x, Pnow);
  const double brute = std::max(sampledRatio(rng, I_rot, Pnow.block<3, 3>(0, 0)),
                                sampledRatio(rng, I_pos_world, Pnow.block<3, 3>(3, 3)));
  EXPECT_GT(lambda, 0.0);
  EXPECT_GE(lambda, brute * (1 - 1e-9));
  EXPECT_NEAR(lambda, brute, 1e-3 * brute);
}

// The position's information turns with the body: the same relative geometry at another heading
// gives the same lambda; a P that is not positive definite gives 0, never NaN.
TEST(FrameSelector, InformationTurnsWithTheBody) {
  std::mt19937 rng(12);
  const StateCov Pb = randomCov(rng, 1e-4);
  const StateCov Pa = afterUpdate(rng, Pb, 40, 2e-2);
  const StateCov Pnow = randomCov(rng, 2e-4);
  const Mat3 R1 = expSO3(Vec3(0.1, 0.2, -0.4));
  const Mat3 Rd = expSO3(Vec3(0.0, 0.0, 1.3));  // the body turned by Rd
  FrameSelector a(SelectorConfig{}, VisualMode::Adaptive), b(SelectorConfig{}, VisualMode::Adaptive);
  a.markUsed(stateAt(Vec3::Zero(), R1), Pb, Pa);
  // b: the same update seen after the turn: world-frame position blocks rotated by Rd.
  StateCov Pb2 = Pb, Pa2 = Pa, Pnow2 = Pnow;
  for (StateCov* M : {&Pb2, &Pa2, &Pnow2}) {
    const StateCov src = *M;
    M->block<3, 3>(3, 3) = Rd * src.block<3, 3>(3, 3) * Rd.transpose();
  }
  b.markUsed(stateAt(Vec3::Zero(), Rd * R1), Pb2, Pa2);
  const double la = a.informationRatio(stateAt(Vec3::Zero(), R1), Pnow);
  const double lb = b.informationRatio(stateAt(Vec3::Zero(), Rd * R1), Pnow2);
  EXPECT_NEAR(la, lb, 1e-9 * la);
  StateCov bad = Pnow;
  bad.block<3, 3>(0, 0) = -Mat3::Identity();
  bad.block<3, 3>(3, 3) = Mat3::Zero();
  EXPECT_EQ(a.informationRatio(stateAt(Vec3::Zero(), R1), bad), 0.0);
  StateCov nan = Pnow;
  nan(4, 4) = std::nan("");
  // A NaN in the position marginal leaves the rotation's ratio: the same as with a position marginal
  // that no image could shrink.
  StateCov rot_only = Pnow;
  rot_only.block<3, 3>(3, 3) = 1e-30 * Mat3::Identity();
  const double expect_rot = a.informationRatio(stateAt(Vec3::Zero(), R1), rot_only);
  EXPECT_GT(expect_rot, 0.0);
  EXPECT_NEAR(a.informationRatio(stateAt(Vec3::Zero(), R1), nan), expect_rot, 1e-9 * expect_rot);
}

// Without motion, an image is used exactly when the last one would shrink a sigma by
// sqrt(1 + information_ratio) or more; information_ratio 0 turns the trigger off.
TEST(FrameSelector, InformationTriggerDecidesWithoutMotion) {
  const NavState x = stateAt(Vec3::Zero(), Mat3::Identity());
  StateCov Pb = 1e-6 * StateCov::Identity();
  StateCov Pa = Pb;
  Pa.block<3, 3>(3, 3) = 0.5e-6 * Mat3::Identity();  // the image halved the position variance: I = 1e6
  for (double ratio : {8.0, 0.0}) {
    SelectorConfig cfg;
    cfg.information_ratio = ratio;
    FrameSelector sel(cfg, VisualMode::Adaptive);
    for (int i = 0; i < cfg.degenerate_frames; ++i) sel.degenerate(true, 0.4);  // a constrained LiDAR
    sel.markUsed(x, Pb, Pa);
    StateCov P = 1e-6 * StateCov::Identity();
    EXPECT_NEAR(sel.informationRatio(x, P), 1.0, 1e-9);
    EXPECT_FALSE(sel.select(x, P, 0.4, false));
    P.block<3, 3>(3, 3) = 7.9e-6 * Mat3::Identity();  // lambda 7.9
    EXPECT_FALSE(sel.select(x, P, 0.4, false));
    P(5, 5) = 8.1e-6;  // lambda 8.1 along z
    EXPECT_EQ(sel.select(x, P, 0.4, false), ratio > 0) << "ratio " << ratio;
  }
}

TEST(FrameSelector, InformationRatioKeyIsCheckedAndNamed) {
  SelectorConfig ok;
  ok.load(ConfigFile::parse("selector:\n  information_ratio: 3\n").root());
  EXPECT_DOUBLE_EQ(ok.information_ratio, 3.0);
  EXPECT_DOUBLE_EQ(SelectorConfig{}.information_ratio, 8.0);
  for (const char* bad : {"-1", ".nan", ".inf"}) {
    SelectorConfig c;
    try {
      c.load(ConfigFile::parse(std::string("selector:\n  information_ratio: ") + bad + "\n").root());
      ADD_FAILURE() << bad << " must be refused";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("selector.information_ratio"), std::string::npos) << e.what();
    }
  }
}
