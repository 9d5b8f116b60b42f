// Photometric update: residual Jacobians vs numeric differences, the plane-induced warp vs its closed
// form, and on a real EuRoC image: a known brightness change is recovered as the inverse exposure, and
// a perturbed pose is pulled back to the truth.
// livo-test-deps: livo_estimation livo_map livo_sensors livo_datasets
#include "livo/datasets/euroc.hpp"
#include "livo/estimation/vio_update.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <random>

using namespace livo;

namespace {

Image syntheticImage(int w, int h, double gain = 1.0) {
  Image img;
  img.width = w;
  img.height = h;
  img.row_stride = w;
  img.data.resize(std::size_t(w) * std::size_t(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.data[std::size_t(y * w + x)] = static_cast<std::uint8_t>(
          std::lround(std::clamp(gain * (128.0 + 50.0 * std::sin(x / 6.0) * std::cos(y / 8.0) + 30.0 * std::sin((x + y) / 13.0)), 0.0, 255.0)));
  return img;
}

CameraConfig pinholeConfig(int w, int h) {
  CameraConfig c;
  c.enabled = true;
  c.width = w;
  c.height = h;
  c.fx = c.fy = 300.0;
  c.cx = (w - 1) / 2.0;
  c.cy = (h - 1) / 2.0;
  return c;
}

/// A visual point on the plane z = depth (camera frame of an identity camera pose) at pixel px, with
/// one observation from `img` taken at the identity pose with inverse exposure 1. False when the
/// patch pyramid does not fit in the image there.
bool planePoint(const CameraModel& cam, const Image& img, const Vec2& px, double depth, VisualPoint& p) {
  Vec3 b;
  if (!cam.unproject(px, b)) return false;
  p = VisualPoint();
  p.p_world = b * (depth / b.z());
  p.normal = Vec3(0, 0, -1);
  VisualObservation o;
  o.px = px;
  if (!extractPatchPyramid(img, px, o.patch)) return false;
  p.obs.push_back(o);
  p.reference = 0;
  return true;
}

VisualPoint planePoint(const CameraModel& cam, const Image& img, const Vec2& px, double depth) {
  VisualPoint p;
  EXPECT_TRUE(planePoint(cam, img, px, depth, p));
  return p;
}

/// Pixel of a world point for state x (camera = IMU frame).
Vec2 pixelOf(const CameraModel& cam, const NavState& x, const Vec3& p_w) {
  Vec2 px;
  cam.project(x.R_world_imu.transpose() * (p_w - x.p_world_imu), px);
  return px;
}

/// The Jacobian tests' scene: a textured image, a pinhole camera at the IMU, one plane point 4 m ahead
/// and a state slightly off the identity.
struct JacobianScene {
  Image img = syntheticImage(320, 240);
  std::unique_ptr<CameraModel> cam = CameraModel::create(pinholeConfig(320, 240));
  Pose T_imu_camera = Pose::Identity();
  VisualPoint p = planePoint(*cam, img, Vec2(150.3, 110.7), 4.0);
  NavState x;
  JacobianScene() {
    x.R_world_imu = expSO3(Vec3(0.002, -0.003, 0.001));
    x.p_world_imu = Vec3(0.01, -0.005, 0.02);
    x.inv_exposure = 1.1;
  }
};

}  // namespace

TEST(VioUpdate, PhotometricJacobianMatchesNumericDifferences) {
  const JacobianScene sc;
  const auto& [img, cam, T_imu_camera, p, x] = sc;
  const Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  int checked = 0;
  for (int level = 0; level < PatchPyramid::kLevels; ++level) {
    for (int row = 0; row < 8; row += 3) {
      for (int col = 0; col < 8; col += 3) {
        double r0;
        Eigen::Matrix<double, 1, 7> H;
        ASSERT_TRUE(photometricResidual(x, img, *cam, T_imu_camera, p, A, level, row, col, r0, &H));
        for (int i = 0; i < 7; ++i) {
          // Steps that move the pixel by about one sample stride: the numeric slope of the 8-bit image
          // is then comparable with the analytic central-difference gradient.
          double eps = 1e-3;
          if (i < 6) {
            StateVec d0 = StateVec::Zero();
            d0[i] = 1e-5;
            const double moved = (pixelOf(*cam, x.boxplus(d0), p.p_world) - pixelOf(*cam, x, p.p_world)).norm();
            eps = std::min(0.05, 1e-5 * double(1 << level) / std::max(moved, 1e-12));
          }
          StateVec d = StateVec::Zero();
          d[i] = eps;
          double rp, rm;
          ASSERT_TRUE(photometricResidual(x.boxplus(d), img, *cam, T_imu_camera, p, A, level, row, col, rp, nullptr));
          ASSERT_TRUE(photometricResidual(x.boxplus(-d), img, *cam, T_imu_camera, p, A, level, row, col, rm, nullptr));
          const double num = (rp - rm) / (2 * eps);
          // The analytic gradient is a central difference over the sample stride: it matches the
          // numeric slope of the bilinear image up to the image's curvature.
          EXPECT_NEAR(H(i), num, 0.15 * std::abs(num) + 3.0) << "level " << level << " column " << i;
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 3 * 9 * 7);
}

// With the camera's time offset t_d: the image was captured at the state's time + t_d, the body moving
// meanwhile. The rows with respect to dtheta and dp at the shifted capture pose, and d r / d t_d,
// against numeric differences (of x.boxplus and of x.time_offset_s).
TEST(VioUpdate, TimeOffsetJacobianMatchesNumericDifferences) {
  const JacobianScene sc;
  const auto& [img, cam, T_imu_camera, p, x_scene] = sc;
  NavState x = x_scene;
  x.v_world = Vec3(0.8, -0.3, 0.4);
  x.time_offset_s = -0.012;
  CaptureMotion motion;
  motion.omega_imu = Vec3(0.4, -0.9, 0.6);
  const auto capturePixel = [&](const NavState& s) {  // through sc: C++17 lambdas cannot capture bindings
    Vec2 px;
    sc.cam->project(imuPoseAtCapture(s, motion).inverse() * sc.p.p_world, px);
    return px;
  };
  // The capture pose moves the pixel (the test is not degenerate), and it is the uniform motion.
  EXPECT_GT((capturePixel(x) - pixelOf(*cam, x, p.p_world)).norm(), 0.5);
  const Pose Tc = imuPoseAtCapture(x, motion);
  EXPECT_LT((Tc.translation() - (x.p_world_imu + x.v_world * x.time_offset_s)).norm(), 1e-15);
  EXPECT_LT((Tc.linear() - x.R_world_imu * expSO3(motion.omega_imu * x.time_offset_s)).norm(), 1e-15);
  const Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  int checked = 0;
  std::vector<double> ratios_pose, ratios_td;  // analytic / numeric where the slope is clear
  for (int level = 0; level < PatchPyramid::kLevels; ++level)
    for (int row = 0; row < 8; row += 3)
      for (int col = 0; col < 8; col += 3) {
        double r0, H_td = 0;
        Eigen::Matrix<double, 1, 7> H;
        ASSERT_TRUE(photometricResidual(x, img, *cam, T_imu_camera, p, A, level, row, col, r0, &H, &motion, &H_td));
        for (int i = 0; i < 7; ++i) {  // dtheta, dp, then (6) t_d in place of the exposure column
          // Steps that move the pixel by about one sample stride (see the test above).
          const auto shifted = [&](double e) {
            NavState s = x;
            if (i < 6) {
              StateVec d = StateVec::Zero();
              d[i] = e;
              s = x.boxplus(d);
            } else {
              s.time_offset_s += e;
            }
            return s;
          };
          const double moved = (capturePixel(shifted(1e-5)) - capturePixel(x)).norm();
          const double eps = std::min(0.05, 1e-5 * double(1 << level) / std::max(moved, 1e-12));
          double rp, rm;
          ASSERT_TRUE(photometricResidual(shifted(eps), img, *cam, T_imu_camera, p, A, level, row, col, rp, nullptr, &motion));
          ASSERT_TRUE(photometricResidual(shifted(-eps), img, *cam, T_imu_camera, p, A, level, row, col, rm, nullptr, &motion));
          const double num = (rp - rm) / (2 * eps);
          const double analytic = i < 6 ? H(i) : H_td;
          // The capture pixel lies a few pixels off the reference here, where the image curves: the
          // analytic gradient (axis-aligned central differences over the stride) and the numeric slope
          // (along the motion) differ by more than at the reference (test above), so each sample gets
          // a wider bound and the ratio's median a tight one.
          EXPECT_NEAR(analytic, num, 0.5 * std::abs(num) + 3.0) << "level " << level << " column " << i;
          if (std::abs(num) > 10.0) (i < 6 ? ratios_pose : ratios_td).push_back(analytic / num);
          ++checked;
        }
      }
  EXPECT_EQ(checked, 3 * 9 * 7);
  for (std::vector<double>* r : {&ratios_pose, &ratios_td}) {
    ASSERT_GE(r->size(), 10u);
    std::nth_element(r->begin(), r->begin() + std::ptrdiff_t(r->size() / 2), r->end());
    EXPECT_NEAR((*r)[r->size() / 2], 1.0, 0.1) << (r == &ratios_td ? "t_d" : "pose");
  }
}

// The update's normal equations, built from per-point moments of the image gradient, intensity and
// residual, equal the brute-force sum of H^T H and H^T r over photometricResidual's rows (one per patch
// pixel), for several points, warps, every level, with and without exposure; points partly outside the
// image contribute the same pixels to both.
TEST(VioUpdate, NormalEquationsFromMomentsEqualTheSumOfPixelRows) {
  const Image img = syntheticImage(320, 240);
  const Image cur = syntheticImage(320, 240, 0.93);
  const auto cam = CameraModel::create(pinholeConfig(320, 240));
  const Pose T_imu_camera = Pose::Identity();
  std::vector<VisualPoint> store;
  std::vector<Eigen::Matrix2d> warps;
  for (const Vec2& px : {Vec2(150.3, 110.7), Vec2(60.2, 40.9), Vec2(250.6, 180.1), Vec2(23.4, 200.2), Vec2(296.0, 23.0)}) {
    VisualPoint p;
    if (!planePoint(*cam, img, px, 3.0 + 0.01 * px.x(), p)) continue;
    store.push_back(p);
    Eigen::Matrix2d A;
    A << 1.02, 0.03, -0.05, 0.97;
    warps.push_back(store.size() % 2 ? A : Eigen::Matrix2d::Identity());
  }
  ASSERT_GE(store.size(), 4u);
  bool partial = false;  // some patch pixels outside the current image
  std::vector<const VisualPoint*> points;
  for (const VisualPoint& p : store) points.push_back(&p);
  NavState x;
  x.R_world_imu = expSO3(Vec3(0.004, -0.003, 0.002));
  x.inv_exposure = 1.07;
  const double inv_var = 1.0 / 68.0;
  // Near the prior, and moved by ~10 px so that the border points' patches leave the image in part.
  for (const Vec3& p_world_imu : {Vec3(0.03, -0.02, 0.01), Vec3(0.1, 0.08, 0.0)})
  for (const bool exposure : {true, false}) {
    x.p_world_imu = p_world_imu;
    for (int level = 0; level < PatchPyramid::kLevels; ++level) {
      Eigen::Matrix<double, 7, 7> HtH = Eigen::Matrix<double, 7, 7>::Zero();
      Eigen::Matrix<double, 7, 1> Htr = Eigen::Matrix<double, 7, 1>::Zero();
      double cost = 0;
      std::size_t n = 0;
      for (std::size_t i = 0; i < points.size(); ++i)
        for (int row = 0; row < PatchPyramid::kSize; ++row)
          for (int col = 0; col < PatchPyramid::kSize; ++col) {
            double r;
            Eigen::Matrix<double, 1, 7> H;
            if (!photometricResidual(x, cur, *cam, T_imu_camera, *points[i], warps[i], level, row, col, r, &H)) continue;
            if (!exposure) H(6) = 0;
            HtH += H.transpose() * H * inv_var;
            Htr += H.transpose() * r * inv_var;
            cost += r * r;
            ++n;
          }
      const PhotometricNormalEquations ne =
          photometricNormalEquations(x, cur, *cam, T_imu_camera, points, warps, level, inv_var, exposure);
      SCOPED_TRACE("level " + std::to_string(level) + (exposure ? " with exposure" : " without exposure") +
                   " at x " + std::to_string(p_world_imu.x()));
      ASSERT_GT(n, 100u);
      if (p_world_imu.x() > 0.05 && level == 2) partial = partial || n < points.size() * 64;
      EXPECT_EQ(ne.pixels, n);
      EXPECT_NEAR(ne.cost, cost, 1e-9 * cost);
      EXPECT_LE((ne.HtRH - HtH).norm(), 1e-9 * HtH.norm());
      EXPECT_LE((ne.HtRz - Htr).norm(), 1e-9 * Htr.norm() + 1e-12);
    }
  }
  EXPECT_TRUE(partial) << "the moved state must put part of a patch outside the image";
}

TEST(VioUpdate, PlaneWarpMatchesClosedForm) {
  // Fronto-parallel plane at 4 m; current camera 1 m closer along the axis: displacements scale by
  // d_cur / d_ref = 3 / 4 from current to reference.
  const auto cam = CameraModel::create(pinholeConfig(320, 240));
  const Image img = syntheticImage(320, 240);
  VisualPoint p = planePoint(*cam, img, Vec2(200, 90), 4.0);
  Pose T_world_cur = Pose::Identity();
  T_world_cur.translation() = Vec3(0, 0, 1.0);
  const Eigen::Matrix2d A = warpRefFromCur(p, p.obs[0], T_world_cur, *cam);
  EXPECT_TRUE(A.isApprox(Eigen::Matrix2d::Identity() * 0.75, 1e-6)) << A;
  // A rotated current view of a tilted plane: the warp is the derivative of the plane homography,
  // checked against finite differences of the exact pixel mapping with a smaller step.
  p.normal = Vec3(0.3, -0.2, -1).normalized();
  T_world_cur.linear() = expSO3(Vec3(0.05, -0.1, 0.2));
  T_world_cur.translation() = Vec3(0.3, -0.1, 0.5);
  const Eigen::Matrix2d A2 = warpRefFromCur(p, p.obs[0], T_world_cur, *cam);
  Vec2 px_cur;
  ASSERT_TRUE(cam->project(T_world_cur.inverse() * p.p_world, px_cur));
  auto mapToRef = [&](const Vec2& q) {
    Vec3 b;
    cam->unproject(q, b);
    const Vec3 dir = T_world_cur.linear() * b;
    const Vec3 c = T_world_cur.translation();
    const double t = p.normal.dot(p.p_world - c) / p.normal.dot(dir);
    Vec2 out;
    cam->project(c + t * dir, out);
    return out;
  };
  Eigen::Matrix2d Anum;
  for (int a = 0; a < 2; ++a) {
    Vec2 e = Vec2::Zero();
    e[a] = 0.01;
    Anum.col(a) = (mapToRef(px_cur + e) - mapToRef(px_cur - e)) / 0.02;
  }
  EXPECT_TRUE(A2.isApprox(Anum, 1e-3)) << A2 << "\n" << Anum;
}

namespace {

struct EurocScene {
  std::unique_ptr<CameraModel> cam;
  Image img;
  std::vector<VisualPoint> points;
};

bool loadEurocScene(EurocScene& s) {
  const std::string dir = std::string(LIVO_SHARED_DATA) + "/euroc_v1_01_micro/mav0/cam0";
  if (!std::filesystem::exists(dir)) return false;
  const EurocCameraCalibration cal = readEurocCameraYaml(dir + "/sensor.yaml");
  CameraConfig cc;
  cc.enabled = true;
  cc.width = cal.width;
  cc.height = cal.height;
  cc.fx = cal.fx;
  cc.fy = cal.fy;
  cc.cx = cal.cx;
  cc.cy = cal.cy;
  cc.distortion = cal.distortion;
  s.cam = CameraModel::create(cc);
  s.img = readGrayImage(dir + "/data/1403715273262142976.png", 0);
  // Points on a plane 3 m away at the most textured pixels of a 30 px grid (gradient energy).
  for (int gy = 30; gy + 30 < s.img.height; gy += 30) {
    for (int gx = 30; gx + 30 < s.img.width; gx += 30) {
      double best = -1;
      Vec2 best_px;
      for (int y = gy; y < gy + 30; y += 3)
        for (int x = gx; x < gx + 30; x += 3) {
          const auto at = [&](int u, int v) { return double(s.img.data[std::size_t(v * s.img.row_stride + u)]); };
          const double g = std::pow(at(x + 1, y) - at(x - 1, y), 2) + std::pow(at(x, y + 1) - at(x, y - 1), 2);
          if (g > best) {
            best = g;
            best_px = Vec2(x, y);
          }
        }
      VisualPoint p;
      if (best > 400 && planePoint(*s.cam, s.img, best_px, 3.0, p)) s.points.push_back(p);
    }
  }
  return true;
}

}  // namespace

TEST(VioUpdate, EurocRecoversKnownBrightnessChangeAsExposure) {
  EurocScene s;
  if (!loadEurocScene(s)) LIVO_SKIP() << "no reference data";
  ASSERT_GT(s.points.size(), 50u);
  // The same view, 30 % darker: tau_k I_k = tau_ref P_ref gives tau_k = 1 / 0.7.
  Image dark = s.img;
  for (auto& v : dark.data) v = static_cast<std::uint8_t>(std::lround(0.7 * v));
  std::vector<VisualPoint*> ptrs;
  for (auto& p : s.points) ptrs.push_back(&p);
  NavState x;
  StateCov P = initialCovariance();
  P(sidx::kExposure, sidx::kExposure) = 0.25;
  VioConfig cfg;
  cfg.outlier_rms = 200;  // the prior exposure is 43 % off: every patch starts far from its reference
  const VioUpdateResult r = visualUpdate(x, P, dark, *s.cam, Pose::Identity(), ptrs, cfg);
  std::cout << "points " << r.points_used << ", rms " << r.rms_before << " -> " << r.rms_after << ", tau " << x.inv_exposure << "\n";
  EXPECT_NEAR(x.inv_exposure, 1.0 / 0.7, 0.02);
  EXPECT_LT(x.p_world_imu.norm(), 0.002);
  EXPECT_LT(rotationAngle(x.R_world_imu) * 180 / M_PI, 0.02);
  EXPECT_LT(r.rms_after, 0.25 * r.rms_before);
}

TEST(VioUpdate, EurocPullsPerturbedPoseBackToTruth) {
  EurocScene s;
  if (!loadEurocScene(s)) LIVO_SKIP() << "no reference data";
  std::vector<VisualPoint*> ptrs;
  for (auto& p : s.points) ptrs.push_back(&p);
  NavState x;
  x.p_world_imu = Vec3(0.015, -0.01, 0.01);
  x.R_world_imu = expSO3(Vec3(0.004, -0.003, 0.005));
  StateCov P = initialCovariance();
  P.block<3, 3>(sidx::kRot, sidx::kRot) = Mat3::Identity() * std::pow(0.01, 2);
  P.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * std::pow(0.03, 2);
  VioConfig cfg;
  cfg.outlier_rms = 100;
  const double rot_before = rotationAngle(x.R_world_imu);
  const VioUpdateResult r = visualUpdate(x, P, s.img, *s.cam, Pose::Identity(), ptrs, cfg);
  const double rot_after = rotationAngle(x.R_world_imu);
  std::cout << "points " << r.points_used << ", rms " << r.rms_before << " -> " << r.rms_after << ", rot "
            << rot_before * 180 / M_PI << " -> " << rot_after * 180 / M_PI << " deg, pos " << x.p_world_imu.norm() * 100 << " cm\n";
  EXPECT_LT(rot_after, 0.1 * rot_before);
  EXPECT_LT(r.rms_after, 0.3 * r.rms_before);
  // Depth is weakly observable from one fronto-parallel plane (translation along the axis changes the
  // patches little): the in-plane position is what the photometric term must fix.
  EXPECT_LT(x.p_world_imu.head<2>().norm(), 0.004);
}

TEST(VioUpdate, PointsNearTheBorderAreRejectedNotRead) {
  const Image img = syntheticImage(320, 240);
  const auto cam = CameraModel::create(pinholeConfig(320, 240));
  // Reference patches cut in the middle, but the points project right at the image border now.
  std::vector<VisualPoint> pts;
  for (const Vec2 px : {Vec2(160, 120), Vec2(150, 100)}) pts.push_back(planePoint(*cam, img, px, 2.0));
  for (auto& p : pts) p.p_world += Vec3(0.52, 0.38, 0.0) * 2.0;  // moves the projection near the corner
  std::vector<VisualPoint*> ptrs{&pts[0], &pts[1]};
  NavState x;
  StateCov P = initialCovariance();
  const VioUpdateResult r = visualUpdate(x, P, img, *cam, Pose::Identity(), ptrs, VioConfig{});
  EXPECT_EQ(r.points_used, 0);
  EXPECT_EQ(r.points_rejected, 2);
  EXPECT_TRUE(x.p_world_imu.isZero());
}
