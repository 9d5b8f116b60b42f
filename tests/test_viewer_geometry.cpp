// Geometry of livo-viewer's drawing (libs/viewer geometry.hpp): the frustum's corners project back onto
// the image corners through the pinhole model, the follow camera sits behind and above the pose and
// turns with it smoothly (message time), the top view sees the whole box (checked with a projection
// built from the camera it returns), robust bounds ignore far outliers.
#include "livo/viewer/geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace livo;
using namespace livo::viewer;

namespace {

Pose yawPose(double yaw, const Vec3& p) {
  Pose T = Pose::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
  T.translation() = p;
  return T;
}

}  // namespace

TEST(ViewerGeometry, FrustumCornersProjectOntoTheImageCorners) {
  const FrustumIntrinsics k{640, 512, 400, 410, 319.5, 255.5};
  ASSERT_TRUE(k.valid());
  EXPECT_FALSE(FrustumIntrinsics{}.valid());
  Pose T_world_cam = Pose::Identity();
  T_world_cam.linear() = (Eigen::AngleAxisd(0.3, Vec3::UnitX()) * Eigen::AngleAxisd(-1.1, Vec3::UnitY())).toRotationMatrix();
  T_world_cam.translation() = Vec3(1, -2, 0.5);
  const auto c = frustumCorners(k, T_world_cam, 0.8);
  EXPECT_LT((c[0] - T_world_cam.translation()).norm(), 1e-12);
  const double u[4] = {0, 640, 640, 0}, v[4] = {0, 0, 512, 512};
  for (int i = 0; i < 4; ++i) {
    const Vec3 p_cam = T_world_cam.inverse() * c[i + 1];
    EXPECT_NEAR(p_cam.z(), 0.8, 1e-12);
    EXPECT_NEAR(k.fx * p_cam.x() / p_cam.z() + k.cx, u[i], 1e-9);
    EXPECT_NEAR(k.fy * p_cam.y() / p_cam.z() + k.cy, v[i], 1e-9);
  }
  EXPECT_EQ(frustumSegments().size(), 8u);
}

TEST(ViewerGeometry, FollowCameraSitsBehindAndAboveAndTurnsSmoothly) {
  FollowConfig cfg;
  cfg.distance_m = 6;
  cfg.height_m = 4;
  cfg.look_ahead_m = 1;
  cfg.heading_tau_s = 0.5;
  FollowCamera follow(cfg);
  const ViewCamera c0 = follow.update(yawPose(M_PI / 2, Vec3(1, 2, 3)), 10.0);  // facing +y
  EXPECT_LT((c0.position - Vec3(1, -4, 7)).norm(), 1e-9);
  EXPECT_LT((c0.focal - Vec3(1, 3, 3)).norm(), 1e-9);
  EXPECT_FALSE(c0.parallel);
  // A sudden turn to facing -x: after one time constant the heading has covered 1 - 1/e of the way.
  const ViewCamera c1 = follow.update(yawPose(M_PI, Vec3(1, 2, 3)), 10.5);
  EXPECT_NEAR(follow.heading(), M_PI / 2 + (1 - std::exp(-1.0)) * (M_PI / 2), 1e-9);
  EXPECT_NEAR(c1.position.z(), 7.0, 1e-9);
  for (int i = 0; i < 100; ++i) follow.update(yawPose(M_PI, Vec3(1, 2, 3)), 10.5 + 0.1 * (i + 1));
  EXPECT_NEAR(std::abs(std::remainder(follow.heading() - M_PI, 2 * M_PI)), 0.0, 1e-6);
  // Across the +-pi wrap the short way round.
  FollowCamera wrap(cfg);
  wrap.update(yawPose(M_PI - 0.1, Vec3::Zero()), 0.0);
  wrap.update(yawPose(-M_PI + 0.1, Vec3::Zero()), 10.0);
  EXPECT_NEAR(std::abs(std::remainder(wrap.heading() - (-M_PI + 0.1), 2 * M_PI)), 0.0, 1e-6);
  // A pose at the same time does not move the heading; reset() jumps.
  const double h = wrap.heading();
  wrap.update(yawPose(0.0, Vec3::Zero()), 10.0);
  EXPECT_DOUBLE_EQ(wrap.heading(), h);
  wrap.reset();
  wrap.update(yawPose(0.3, Vec3::Zero()), 11.0);
  EXPECT_NEAR(wrap.heading(), 0.3, 1e-12);
}

TEST(ViewerGeometry, TopViewSeesTheWholeBox) {
  const Vec3 lo(-3, -1, 0), hi(5, 2, 3);
  for (const double aspect : {1.6, 0.5}) {
    const ViewCamera c = topCamera(lo, hi, aspect, 0.05);
    ASSERT_TRUE(c.parallel);
    EXPECT_NEAR(c.focal.x(), 1.0, 1e-12);
    EXPECT_NEAR(c.focal.y(), 0.5, 1e-12);
    EXPECT_GT(c.position.z(), hi.z());
    // Parallel projection looking down with y up: screen x = world x, screen y = world y, and the
    // visible half-extents are (aspect * scale, scale).
    for (const double x : {lo.x(), hi.x()})
      for (const double y : {lo.y(), hi.y()}) {
        EXPECT_LE(std::abs(x - c.focal.x()), aspect * c.parallel_scale) << aspect;
        EXPECT_LE(std::abs(y - c.focal.y()), c.parallel_scale) << aspect;
      }
    // Tight: the box fills the limiting direction up to the margin.
    const double fill = std::max((hi.x() - lo.x()) / (2 * aspect * c.parallel_scale), (hi.y() - lo.y()) / (2 * c.parallel_scale));
    EXPECT_NEAR(fill, 1.0 / 1.1, 1e-9) << aspect;
  }
  // With the top quarter kept free: the whole box lies in the lower three quarters of the view.
  const ViewCamera c = topCamera(lo, hi, 1.0, 0.0, 0.25);
  const double top_of_view = c.focal.y() + c.parallel_scale, bottom = c.focal.y() - c.parallel_scale;
  EXPECT_LE(hi.y(), top_of_view - 0.25 * 2 * c.parallel_scale + 1e-9);
  EXPECT_GE(lo.y(), bottom - 1e-9);
  EXPECT_NEAR(std::max((hi.x() - lo.x()) / (2 * c.parallel_scale), (hi.y() - lo.y()) / (1.5 * c.parallel_scale)), 1.0, 1e-9);
}

TEST(ViewerGeometry, RobustBoundsIgnoreFarOutliers) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.f, 10.f);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 10000; ++i) pts.emplace_back(u(rng), u(rng) * 0.5f, u(rng) * 0.3f);
  for (int i = 0; i < 10; ++i) pts.emplace_back(1000.f, -1000.f, 500.f);  // 0.1 % far away
  Vec3 lo, hi;
  robustBounds(pts, 0.005, lo, hi);
  EXPECT_NEAR(lo.x(), 0.05, 0.05);
  EXPECT_NEAR(hi.x(), 9.95, 0.05);
  EXPECT_NEAR(hi.y(), 4.975, 0.05);
  EXPECT_NEAR(hi.z(), 2.985, 0.05);
  robustBounds({}, 0.01, lo, hi);
  EXPECT_EQ(lo, Vec3::Zero());
  ViewMode m = ViewMode::kFollow;
  EXPECT_TRUE(parseViewMode("free", m));
  EXPECT_EQ(m, ViewMode::kFree);
  EXPECT_FALSE(parseViewMode("side", m));
  EXPECT_EQ(nextViewMode(ViewMode::kFree), ViewMode::kFollow);
}
