// libs/sim: camera pixels vs brute-force rays and analytic geometry (photo texture on a wall), exposure
// jitter and pixel noise vs their sigmas, texture footprint filtering.
#include "sim_test_util.hpp"

#include "livo/sim/simulator.hpp"
#include "livo/sim/texture.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <string>

using namespace livo;
using namespace livo::sim;
using namespace livo::sim::test;

// ---------------------------------------------------------------- camera

TEST(SimCamera, PixelsShowTheSurfaceTheirRaysHit) {
  for (const std::string world_model : {"room/pinhole", "room/equidistant", "street/pinhole"}) {
    SCOPED_TRACE(world_model);
    const std::string world = world_model.substr(0, world_model.find('/'));
    const std::string model = world_model.substr(world_model.find('/') + 1);
    SimScenario sc = makeScenario(world, world == "street" ? "spinning32" : "avia");
    sc.camera.model = model;
    sc.camera.distortion = model == "pinhole" ? std::vector<double>{-0.2, 0.05, 0.001, -0.002}
                                              : std::vector<double>{0.02, -0.01, 0.003, -0.001};
    if (model == "equidistant") {
      sc.camera.width = sc.camera.height = 72;
      sc.camera.fx = sc.camera.fy = 25.0;
      sc.camera.cx = sc.camera.cy = 35.5;
      sc.camera.max_angle_deg = 90.0;
    }
    sc.extrinsics.T_imu_camera.translation() = Vec3(0.1, 0.03, -0.02);
    Simulator sim(sc);
    ImageTruth truth;
    const Image img = sim.renderImage(28, &truth);  // t = 2.837 s, moving
    ASSERT_EQ(img.utime, sim.startUtime() + 2'837'000);
    std::size_t sky = 0;
    EXPECT_TRUE(truth.T_world_camera.isApprox(sim.T_world_camera(img.utime), 1e-12));
    const SimCameraModel& cam = sim.camera();
    std::size_t invalid = 0;
    for (int r = 0; r < img.height; ++r)
      for (int c = 0; c < img.width; ++c) {
        const std::size_t i = static_cast<std::size_t>(r) * img.width + c;
        if (!cam.valid()[i]) {
          ASSERT_EQ(img.data[i], 0);
          ++invalid;
          continue;
        }
        Vec3 ray;
        ASSERT_TRUE(cam.unproject({c, r}, ray));
        ASSERT_LT((ray - cam.rays()[i].cast<double>()).norm(), 1e-6);
        const Vec3 dir = truth.T_world_camera.linear() * cam.rays()[i].cast<double>();
        const Hit hit = sim.world().raycastBruteForce(truth.T_world_camera.translation(), dir, 2000.0, cam.pixelAngle()[i]);
        ASSERT_TRUE(hit.valid || world == "street");  // the room is closed; the street has a sky
        double radiance = World::skyRadiance(dir);
        sky += !hit.valid;
        if (hit.valid) {
          ASSERT_LT(sim.world().distanceToSurface(hit.point), 1e-9 * (1.0 + hit.distance));
          Eigen::Vector2d uv;
          ASSERT_TRUE(cam.project(truth.T_world_camera.inverse() * hit.point, uv));
          ASSERT_LT((uv - Eigen::Vector2d(c, r)).norm(), 1e-5);
          radiance = sim.world().radiance(hit);
        }
        const long expected = std::clamp(std::lround(kGrayPerRadiance * truth.gain * radiance), 0L, 255L);
        ASSERT_EQ(img.data[i], expected) << "pixel " << c << "," << r;
      }
    EXPECT_EQ(invalid > 100u, model == "equidistant");  // fisheye corners lie beyond 90 deg
    EXPECT_EQ(sky > 50u, world == "street");
  }
}

TEST(SimCamera, PhotoTextureOnAWallMatchesAnalyticGeometry) {
  // A synthetic photo: smooth gradient plus fine stripes.
  const std::string png = std::string(LIVO_BINARY_DIR) + "/test_sim_texture.png";
  cv::Mat photo(128, 160, CV_8U);
  for (int r = 0; r < photo.rows; ++r)
    for (int c = 0; c < photo.cols; ++c) photo.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>((c + r) % 200 + ((c / 4) % 2) * 50);
  ASSERT_TRUE(cv::imwrite(png, photo));
  SimScenario sc = makeScenario("wall");
  sc.world.texture = "images";
  sc.world.texture_images = {png};
  sc.world.texture_tile_m = 1.5;
  Simulator sim(sc);
  ImageTruth truth;
  const Image img = sim.renderImage(2, &truth);  // t = 0.237 s, at rest
  const Pose& T = truth.T_world_camera;
  const Vec3 o = T.translation();
  const double face_x = sc.world.size_m.x();
  const Vec3 center(face_x + 0.25, 0.0, 1.4), half(0.25, 20.0, 10.0);
  std::size_t exact = 0, total = 0;
  double sum = 0, sum2 = 0;
  for (int r = 0; r < img.height; ++r)
    for (int c = 0; c < img.width; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * img.width + c;
      const Vec3 d = T.linear() * sim.camera().rays()[i].cast<double>();
      ASSERT_GT(d.x(), 0.0);
      // Ray-plane intersection with the wall face x = face_x; texture coordinates of face -x of box 0.
      const double t = (face_x - o.x()) / d.x();
      const Vec3 q = o + t * d - center;
      Hit h;
      h.valid = true;
      h.normal = Vec3(-1, 0, 0);
      h.albedo = sim.world().albedoAt(1, q.y() + half.y(), q.z() + half.z(), sim.camera().pixelAngle()[i] * t / d.x());
      const long expected = std::clamp(std::lround(kGrayPerRadiance * truth.gain * sim.world().radiance(h)), 0L, 255L);
      ASSERT_LE(std::abs(img.data[i] - expected), 1) << c << "," << r;
      exact += img.data[i] == expected;
      ++total;
      sum += img.data[i];
      sum2 += img.data[i] * img.data[i];
    }
  EXPECT_GT(exact, total * 99 / 100);
  EXPECT_GT(std::sqrt(sum2 / total - std::pow(sum / total, 2)), 10.0);  // the photo is visible
  std::remove(png.c_str());
}

TEST(SimCamera, ExposureJitterAndPixelNoiseFollowTheirSigmas) {
  SimScenario sc = makeScenario("room");
  sc.camera.exposure_jitter = 0.2;
  Simulator quiet(sc);
  double s1 = 0, s2 = 0;
  const int frames = 60;
  for (int k = 0; k < frames; ++k) {
    ImageTruth t;
    quiet.renderImage(k, &t);
    s1 += std::log(t.gain);
    s2 += std::log(t.gain) * std::log(t.gain);
  }
  EXPECT_NEAR(std::sqrt(s2 / frames - std::pow(s1 / frames, 2)), 0.2, 0.06);
  sc.camera.pixel_noise = 3.0;
  Simulator noisy(sc);
  const Image a = quiet.renderImage(30), b = noisy.renderImage(30);
  double e2 = 0;
  int n = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    if (a.data[i] < 15 || a.data[i] > 240) continue;  // away from clamping
    e2 += std::pow(b.data[i] - a.data[i], 2);
    ++n;
  }
  // Rounding adds 1/12 gray level^2.
  EXPECT_NEAR(std::sqrt(e2 / n), std::sqrt(9.0 + 1.0 / 12.0), 0.25);
}

// ---------------------------------------------------------------- textures and world

TEST(SimTexture, FootprintFilteringRemovesDetailFinerThanTheFootprint) {
  // Photos: a one-pixel checkerboard seen with a large footprint averages to grey.
  std::vector<float> checker(64 * 64);
  for (int r = 0; r < 64; ++r)
    for (int c = 0; c < 64; ++c) checker[static_cast<std::size_t>(r) * 64 + c] = ((r + c) % 2) ? 1.f : 0.f;
  const MipImage mip = TextureBank::buildMip(64, 64, checker);
  for (double x = 0.3; x < 200.0; x += 7.77) {
    EXPECT_NEAR(TextureBank::sampleMip(mip, x, 0.61 * x, 4.0), 0.5, 1e-6);
    const double fine = TextureBank::sampleMip(mip, std::floor(x) + 0.5, std::floor(0.61 * x) + 0.5, 0.0);
    EXPECT_TRUE(fine == 0.0 || fine == 1.0);
  }
  // Noise: with footprint F, samples F/2 apart differ far less than with a fine footprint.
  const TextureBank bank(TextureKind::Noise, {}, 1.0, 2.0);
  const SurfaceStyle style = bank.makeStyle(3, 5);
  const double F = 0.05;
  double fine = 0.0, coarse = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const double u = 0.0137 * k, v = 0.0071 * k;
    fine += std::abs(bank.albedo(style, u, v, 1e-4) - bank.albedo(style, u + 0.5 * F, v, 1e-4));
    coarse += std::abs(bank.albedo(style, u, v, F) - bank.albedo(style, u + 0.5 * F, v, F));
  }
  EXPECT_LT(coarse, 0.6 * fine);
}
