// Geometric verification of loop candidates (libs/loop loop_verifier): simulator ground truth for the
// relative pose of two visits to one place, a wrong place, an odometry too far off, too few points.
// livo-test-deps: livo_sim
// livo-test-whole
#include "livo/loop/loop_verifier.hpp"
#include "livo/loop/place_descriptor.hpp"
#include "loop_test_util.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <limits>

namespace livo {
namespace {

using test::inKeyframe;
using test::revisitScenario;
using test::worldScan;

struct Visit {
  std::int64_t scan = 0;
  Pose T = Pose::Identity();  // body pose at the scan's start
  std::vector<Vec3> local;    // the scan in its keyframe frame
  PlaceDescriptor descriptor;
};

class LoopVerify : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sim_ = new sim::Simulator(revisitScenario());
    first_ = visit(100);  // 10 s in, first lap
    // The scan of the second lap nearest to it (the laps take about 41 s).
    double best = std::numeric_limits<double>::infinity();
    std::int64_t best_j = 0;
    for (std::int64_t j = 450; j < 550; ++j) {
      const double d = (sim_->T_world_imu(sim_->lidarUtime(j)).translation() - first_.T.translation()).norm();
      if (d < best) best = d, best_j = j;
    }
    second_ = visit(best_j);
    elsewhere_ = visit(best_j + 100);  // 80 m further along the block
  }
  static void TearDownTestSuite() { delete sim_; }
  static Visit visit(std::int64_t j) {
    Visit v;
    v.scan = j;
    v.T = sim_->T_world_imu(sim_->lidarUtime(j));
    v.local = inKeyframe(worldScan(*sim_, j), v.T);
    v.descriptor = PlaceDescriptor::compute(v.local, PlaceDescriptorConfig{});
    return v;
  }
  // The true pose of b's keyframe frame in a's.
  static Pose truth(const Visit& a, const Visit& b) { return keyframeFrame(a.T).inverse() * keyframeFrame(b.T); }
  static LoopVerifyConfig config() {
    LoopVerifyConfig c;
    c.range_sigma_m = sim_->scenario().lidar.range_noise_m;
    c.bearing_sigma_deg = sim_->scenario().lidar.beam_noise_deg;
    return c;
  }
  // A drifted odometry guess: `dx` metres and `dyaw_deg` off the truth.
  static Pose drifted(const Pose& T, double dx, double dyaw_deg) {
    Pose D = Pose::Identity();
    D.linear() = Eigen::AngleAxisd(dyaw_deg * M_PI / 180.0, Vec3::UnitZ()).toRotationMatrix();
    D.translation() = Vec3(dx, -0.5 * dx, 0.1);
    return D * T;
  }

  static sim::Simulator* sim_;
  static Visit first_, second_, elsewhere_;
};
sim::Simulator* LoopVerify::sim_ = nullptr;
Visit LoopVerify::first_, LoopVerify::second_, LoopVerify::elsewhere_;

TEST_F(LoopVerify, TwoVisitsToOnePlaceGiveTheTrueRelativePose) {
  const Pose gt = truth(first_, second_);
  ASSERT_LT(gt.translation().norm(), 2.0) << "the second lap passes within 2 m of the first";
  const PlaceMatch m = second_.descriptor.match(first_.descriptor);
  LoopVerifier v(config());
  // The odometry has drifted 1.5 m and 4 deg over the lap (340 m).
  const LoopCheck c = v.verify(first_.local, second_.local, m.yaw_rad, drifted(gt, 1.5, 4.0), 340.0);
  const double dp = (c.T_cand_query.translation() - gt.translation()).norm();
  const double dr = rotationAngle(gt.linear().transpose() * c.T_cand_query.linear()) * 180.0 / M_PI;
  std::printf("revisit: gt %.2f m apart, overlap %.3f, rms %.3f m, %d iterations, error %.4f m %.4f deg (%s)\n",
              gt.translation().norm(), c.overlap, c.rms_m, c.iterations, dp, dr, toString(c.reason));
  EXPECT_TRUE(c.accepted) << toString(c.reason);
  // 2026-12-06: 1.6 mm, 0.020 deg, overlap 0.467, rms 2.2 cm (the scans' clutter and noise).
  EXPECT_LT(dp, 0.004);
  EXPECT_LT(dr, 0.04);
  EXPECT_GT(c.overlap, 0.35);
  EXPECT_EQ(v.counts().accepted, 1);
}

TEST_F(LoopVerify, AnotherPlaceIsRejected) {
  LoopVerifier v(config());
  const PlaceMatch m = elsewhere_.descriptor.match(first_.descriptor);
  // An odometry that claims they are the same place: the geometry must refuse.
  const LoopCheck c = v.verify(first_.local, elsewhere_.local, m.yaw_rad, Pose::Identity(), 340.0);
  std::printf("elsewhere: overlap %.3f, rms %.3f m (%s)\n", c.overlap, c.rms_m, toString(c.reason));
  EXPECT_FALSE(c.accepted);
  EXPECT_NE(c.reason, LoopReject::Inconsistent) << "rejected on the geometry, not on the odometry";
  EXPECT_EQ(v.counts().total(), 1);
  EXPECT_EQ(v.counts().accepted, 0);
}

TEST_F(LoopVerify, AnOdometryBeyondTheDriftBoundIsRejectedAsInconsistent) {
  const Pose gt = truth(first_, second_);
  const PlaceMatch m = second_.descriptor.match(first_.descriptor);
  LoopVerifier v(config());
  // 100 m between: 2 m + 5 % of 100 m = 7 m of drift allowed; the odometry is 12 m off.
  const LoopCheck c = v.verify(first_.local, second_.local, m.yaw_rad, drifted(gt, 12.0, 0.0), 100.0);
  EXPECT_EQ(c.reason, LoopReject::Inconsistent) << toString(c.reason);
  EXPECT_GT(c.odometry_gap_m, 7.0);
  EXPECT_EQ(v.counts().inconsistent, 1);
  // The same with the drift bound of a 300 m path (17 m) is accepted.
  EXPECT_TRUE(v.verify(first_.local, second_.local, m.yaw_rad, drifted(gt, 12.0, 0.0), 300.0).accepted);
}

TEST_F(LoopVerify, TooFewPointsAreCountedNotRegistered) {
  LoopVerifier v(config());
  const LoopCheck c = v.verify(first_.local, {Vec3(1, 2, 3), Vec3(NAN, 0, 0)}, 0.0, Pose::Identity(), 340.0);
  EXPECT_EQ(c.reason, LoopReject::TooFewPoints);
  EXPECT_EQ(v.verify({}, second_.local, 0.0, Pose::Identity(), 340.0).reason, LoopReject::TooFewPoints);
  EXPECT_EQ(v.counts().too_few_points, 2);
  EXPECT_EQ(v.counts().total(), 2);
}

TEST(LoopVerifyConfig, ResidualBoundFollowsTheLidarNoise) {
  const ConfigFile f = ConfigFile::parse("loop: {}\n", "rig.yaml");
  LoopVerifyConfig a, b;
  a.load(f.root().section("loop"), 0.02, 0.1);
  b.load(f.root().section("loop"), 0.10, 0.1);
  EXPECT_NEAR(a.maxRms(), 3.0 * std::sqrt(0.02 * 0.02 + 0.0025), 1e-12);
  EXPECT_GT(b.maxRms(), a.maxRms());
  const ConfigFile bad = ConfigFile::parse("loop:\n  min_overlap: 1.5\n", "rig.yaml");
  LoopVerifyConfig c;
  EXPECT_THROW(c.load(bad.root().section("loop"), 0.02, 0.1), ConfigError);
}

}  // namespace
}  // namespace livo
