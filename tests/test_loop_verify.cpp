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
  std::printf("true loop: sigma_min %.3f (loop.min_sigma %.2f)\n", c.sigma_min, config().min_sigma);
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

// A corridor: two walls and a floor, nothing across its axis. Two views 2 m apart along it look the same,
// the registration has nothing to slide against and converges where it starts: without the degeneracy
// check that would be a loop 2 m off. The simulator's corridor scans are rejected too.
TEST(LoopVerifyCorridor, ARegistrationFreeAlongTheCorridorIsRejectedAsDegenerate) {
  std::vector<Vec3> corridor;
  for (double x = -30.0; x <= 30.0; x += 0.2)
    for (double t = -1.5; t <= 1.5; t += 0.2) {
      corridor.emplace_back(x, t, -1.5);          // floor
      corridor.emplace_back(x, -1.5, t);          // walls
      corridor.emplace_back(x, 1.5, t);
    }
  std::vector<Vec3> later = corridor;  // the same view 2 m further along (x), cut to the same extent
  for (Vec3& p : later) p.x() -= 2.0;
  LoopVerifyConfig cfg;
  cfg.range_sigma_m = 0.02;
  cfg.bearing_sigma_deg = 0.03;
  LoopVerifier v(cfg);
  const LoopCheck c = v.verify(corridor, later, 0.0, Pose::Identity(), 5.0);
  std::printf("synthetic corridor: registered %.2f m along it (truth 2 m), sigma_min %.4f: %s\n",
              c.T_cand_query.translation().x(), c.sigma_min, toString(c.reason));
  EXPECT_EQ(c.reason, LoopReject::Degenerate);
  EXPECT_LT(c.sigma_min, 0.01);
  EXPECT_EQ(v.counts().degenerate, 1);
  cfg.min_sigma = 0.0;
  LoopVerifier off(cfg);
  const LoopCheck slid = off.verify(corridor, later, 0.0, Pose::Identity(), 5.0);
  EXPECT_TRUE(slid.accepted) << "without the check: " << toString(slid.reason);
  EXPECT_GT(std::abs(slid.T_cand_query.translation().x() - 2.0), 1.0) << "and it would be a loop metres off";

  // The simulator's corridor, two scans 2 m apart: not accepted either (here the registration slides away).
  const sim::Simulator s(sim::loadScenarioFile(std::string(LIVO_SOURCE_DIR) + "/config/sim/corridor.yaml"));
  auto at = [&](std::int64_t j) { return s.T_world_imu(s.lidarUtime(j)); };
  std::int64_t b = 61;
  while ((at(b).translation() - at(60).translation()).norm() < 2.0) ++b;
  LoopVerifyConfig sc = cfg;
  sc.min_sigma = LoopVerifyConfig{}.min_sigma;
  LoopVerifier sv(sc);
  const LoopCheck sim_check = sv.verify(inKeyframe(worldScan(s, 60), at(60)), inKeyframe(worldScan(s, b), at(b)), 0.0,
                                        Pose::Identity(), 5.0);
  std::printf("simulated corridor: %s, sigma_min %.4f\n", toString(sim_check.reason), sim_check.sigma_min);
  EXPECT_FALSE(sim_check.accepted);
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
