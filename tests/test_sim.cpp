// libs/sim against its own ground truth: trajectory derivatives vs finite differences, IMU integrated
// back to the trajectory (RK4), noise statistics vs the configured densities, LiDAR points on the
// world's surfaces at their own times, camera pixels vs brute-force rays and analytic geometry,
// footprint filtering, determinism, the corridor's degeneracy, the shipped scenarios and rig configs.
#include "livo/common/config.hpp"
#include "livo/sim/random.hpp"
#include "livo/sim/simulator.hpp"
#include "livo/sim/texture.hpp"
#include "livo/sim/world_gen.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

using namespace livo;
using namespace livo::sim;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A small, fast scenario; noise-free unless `noisy`.
SimScenario makeScenario(const std::string& world, const std::string& lidar = "avia", bool noisy = false) {
  SimScenario s;
  s.source = "test";
  s.seed = 7;
  s.duration_s = 4.0;
  s.world.kind = world;
  if (world == "corridor") s.world.size_m = {200.0, 2.4, 2.8};
  if (world == "street") s.world.size_m = {300.0, 160.0, 20.0};
  if (world == "wall") s.world.size_m = {3.0, 40.0, 20.0};
  s.world.clutter = 0.7;
  s.trajectory.speed_mps = world == "street" ? 8.0 : 1.2;
  s.trajectory.static_s = 1.0;
  s.trajectory.ramp_s = 1.0;
  s.lidar.model = lidar;
  s.lidar.range_noise_m = noisy ? 0.01 : 0.0;
  s.lidar.beam_noise_deg = noisy ? 0.03 : 0.0;
  if (!noisy) {
    s.imu.gyro_noise = s.imu.accel_noise = s.imu.gyro_bias_walk = s.imu.accel_bias_walk = 0.0;
    s.camera.pixel_noise = 0.0;
    s.camera.exposure_jitter = 0.0;
  }
  s.camera.width = 64;
  s.camera.height = 48;
  s.camera.fx = s.camera.fy = 40.0;
  s.camera.cx = 31.5;
  s.camera.cy = 23.5;
  return s;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Utime t0Utime(const Simulator& sim, double t) { return sim.startUtime() + fromSeconds(t); }

}  // namespace

// ---------------------------------------------------------------- scenarios and rig configs

TEST(SimScenario, ShippedScenariosRunAndMatchTheirRigConfigs) {
  for (const std::string name : {"room", "corridor", "street", "wall", "demo"}) {
    SCOPED_TRACE(name);
    SimScenario sc = loadScenarioFile(std::string(LIVO_SOURCE_DIR) + "/config/sim/" + name + ".yaml");
    sc.duration_s = 0.15;  // a little of every sensor
    Simulator sim(sc);
    int imu = 0, scans = 0, images = 0;
    SimEvent ev;
    while (sim.next(ev)) {
      imu += ev.kind == SimEvent::Kind::Imu;
      scans += ev.kind == SimEvent::Kind::Lidar && ev.scan.points.size() > 1000;
      images += ev.kind == SimEvent::Kind::Image && !ev.image.empty();
    }
    EXPECT_EQ(imu, 30);
    EXPECT_EQ(scans, 2);
    EXPECT_EQ(images, 2);
    std::ostringstream rig;
    sim.writeRigConfig(rig);
    EXPECT_EQ(rig.str(), readFile(std::string(LIVO_SOURCE_DIR) + "/config/sim_" + name + ".yaml"))
        << "regenerate with: livo-sim --scenario config/sim/" << name << ".yaml ... --rig config/sim_" << name << ".yaml";
  }
}

TEST(SimScenario, UnknownKeysAndBadValuesNameTheKey) {
  auto message = [](const std::string& yaml) {
    try {
      parseScenario(yaml);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("world:\n  kind: room\n  sise_m: [1, 2, 3]\n").find("world.sise_m"), std::string::npos);
  EXPECT_NE(message("lidar:\n  model: velodyne\n").find("lidar.model"), std::string::npos);
  EXPECT_NE(message("trajectory:\n  kind: waypoints\n").find("trajectory.waypoints"), std::string::npos);
  EXPECT_NE(message("camera:\n  distortion: [0, 0]\n").find("camera.distortion"), std::string::npos);
  EXPECT_NE(message("imu:\n  rate_hz: abc\n").find("imu.rate_hz"), std::string::npos);
  EXPECT_EQ(message("seed: 3\nworld:\n  kind: wall\n"), "no error");
}

TEST(SimRig, RigConfigHasExactlyTheReadmeKeys) {
  SimScenario sc = makeScenario("street", "spinning32");
  Simulator sim(sc);
  std::ostringstream out;
  sim.writeRigConfig(out);
  const ConfigFile f = ConfigFile::parse(out.str(), "rig");
  const ConfigNode root = f.root();
  std::string env, model, cam_model;
  root.get("environment", env);
  EXPECT_EQ(env, "outdoor");
  const ConfigNode imu = root.section("imu");
  double d;
  int i;
  for (const char* k : {"rate_hz", "gyro_noise", "accel_noise", "gyro_bias_walk", "accel_bias_walk", "time_offset_s"})
    imu.require(k, d);
  imu.require("init_samples", i);
  const ConfigNode lidar = root.section("lidar");
  lidar.require("model", model);
  EXPECT_EQ(model, "spinning32");
  Eigen::Isometry3d T;
  lidar.require("T_imu_lidar", T);
  EXPECT_TRUE(T.isApprox(sc.extrinsics.T_imu_lidar, 1e-9));
  for (const char* k : {"time_offset_s", "blind_m", "max_range_m", "range_noise_m", "beam_noise_deg"}) lidar.require(k, d);
  lidar.require("point_filter_num", i);
  const ConfigNode cam = root.section("camera");
  bool enabled = false;
  cam.require("enabled", enabled);
  EXPECT_TRUE(enabled);
  cam.require("model", cam_model);
  cam.require("width", i);
  EXPECT_EQ(i, sc.camera.width);
  cam.require("height", i);
  for (const char* k : {"fx", "fy", "cx", "cy", "scale", "time_offset_s", "pixel_noise"}) cam.require(k, d);
  std::vector<double> dist;
  cam.require("distortion", dist);
  cam.require("T_imu_camera", T);
  EXPECT_TRUE(T.isApprox(sc.extrinsics.T_imu_camera, 1e-9));
  const ConfigNode sel = root.section("selector");
  for (const char* k : {"degeneracy_threshold", "tau_translation_m", "tau_rotation_deg"}) sel.require(k, d);
  sel.require("degenerate_frames", i);
  EXPECT_NO_THROW(f.checkAllKeysUsed());
}

// ---------------------------------------------------------------- trajectory

TEST(SimTrajectory, DerivativesMatchFiniteDifferencesAndLimitsHold) {
  std::vector<SimScenario> cases;
  for (const std::string kind : {"loop", "lissajous", "waypoints"}) {
    SimScenario s = makeScenario("room");
    s.trajectory.kind = kind;
    if (kind == "waypoints") s.trajectory.waypoints = {-2, -2, 1.3, 2, -2.5, 1.5, 3, 2, 1.2, -1, 2.5, 1.6, -3, 0, 1.4};
    cases.push_back(s);
  }
  cases.push_back(makeScenario("wall"));
  cases.back().trajectory.look_at = {12.0, 0.0, 1.4};
  for (const auto& sc : cases) {
    SCOPED_TRACE(sc.world.kind + "/" + sc.trajectory.kind);
    const SimTrajectory tr(sc.trajectory, sc.world);
    // At rest during the static period.
    for (double t = 0.0; t <= sc.trajectory.static_s; t += 0.1) {
      const BodyState s = tr.state(t);
      EXPECT_EQ(s.v_world.norm(), 0.0);
      EXPECT_EQ(s.a_world.norm(), 0.0);
      EXPECT_EQ(s.omega_body.norm(), 0.0);
      EXPECT_TRUE(s.T_world_imu.isApprox(tr.pose(0.0), 0.0));
    }
    const double h = 1e-4;
    double max_speed = 0.0, max_rate = 0.0, worst_heading = 0.0;
    for (double t = 0.3; t < 40.0; t += 0.0371) {
      const BodyState s = tr.state(t), sp = tr.state(t + h), sm = tr.state(t - h);
      const Vec3 v_num = (sp.T_world_imu.translation() - sm.T_world_imu.translation()) / (2 * h);
      const Vec3 a_num = (sp.v_world - sm.v_world) / (2 * h);
      const Vec3 w_num = logSO3(sm.T_world_imu.linear().transpose() * sp.T_world_imu.linear()) / (2 * h);
      ASSERT_LT((s.v_world - v_num).norm(), 1e-6) << "t " << t;
      ASSERT_LT((s.a_world - a_num).norm(), 2e-3) << "t " << t;  // jerk is piecewise constant
      ASSERT_LT((s.omega_body - w_num).norm(), 1e-5) << "t " << t;
      max_speed = std::max(max_speed, s.v_world.norm());
      max_rate = std::max(max_rate, s.omega_body.norm());
      // Body x roughly along the travel direction (unless facing a target).
      const Vec3 x = s.T_world_imu.linear().col(0);
      if (sc.trajectory.look_at.empty() && t > 3.0 && s.v_world.head<2>().norm() > 0.2)
        worst_heading = std::max(worst_heading, std::acos(std::clamp(x.head<2>().normalized().dot(s.v_world.head<2>().normalized()), -1.0, 1.0)));
    }
    EXPECT_LE(max_speed, sc.trajectory.speed_mps * 1.002);
    EXPECT_LE(max_rate, sc.trajectory.max_rot_dps * kPi / 180.0 * 1.002);
    EXPECT_GT(max_speed, 0.3 * sc.trajectory.speed_mps);
    EXPECT_LT(worst_heading, 25.0 * kPi / 180.0);
  }
}

// ---------------------------------------------------------------- IMU

TEST(SimImu, IntegratesBackToTheTrajectory) {
  SimScenario sc = makeScenario("room");
  sc.duration_s = 8.0;
  Simulator sim(sc);
  std::vector<ImuSample> imu;
  std::vector<ImuTruth> truth;
  sim.run({[&](const ImuSample& s, const ImuTruth& t) {
             imu.push_back(s);
             truth.push_back(t);
           },
           nullptr, nullptr});
  ASSERT_EQ(imu.size(), 1600u);
  EXPECT_EQ(imu.front().utime, static_cast<Utime>(1'700'000'000'000'000));
  // Exact: no noise, no bias. At rest the accelerometer reads +g along world z.
  for (std::size_t k = 0; k < imu.size(); ++k) {
    ASSERT_EQ((imu[k].gyro - truth[k].gyro).norm(), 0.0);
    ASSERT_EQ((imu[k].accel - truth[k].accel).norm(), 0.0);
  }
  EXPECT_NEAR((truth[10].T_world_imu.linear() * imu[10].accel - Vec3(0, 0, kGravity)).norm(), 0.0, 1e-12);

  // RK4 over pairs of samples (step 2 dt, midpoint = the odd sample) on q, v, p:
  // q' = q (x) [0, w] / 2, v' = R(q) f + g, p' = v.
  struct State {
    Quat q;
    Vec3 v, p;
  };
  auto deriv = [](const State& s, const ImuSample& m, State& d) {
    const Quat w(0.0, m.gyro.x(), m.gyro.y(), m.gyro.z());
    d.q.coeffs() = 0.5 * (s.q * w).coeffs();
    d.v = s.q.toRotationMatrix() * m.accel - Vec3(0, 0, kGravity);
    d.p = s.v;
  };
  auto add = [](const State& s, const State& d, double h) {
    State r;
    r.q.coeffs() = s.q.coeffs() + h * d.q.coeffs();
    r.v = s.v + h * d.v;
    r.p = s.p + h * d.p;
    return r;
  };
  State s{Quat(truth[0].T_world_imu.linear()), truth[0].v_world, truth[0].T_world_imu.translation()};
  const double h = 2.0 / sc.imu.rate_hz;
  double worst_p = 0.0, worst_r = 0.0;
  for (std::size_t k = 0; k + 2 < imu.size(); k += 2) {
    State k1, k2, k3, k4;
    deriv(s, imu[k], k1);
    deriv(add(s, k1, h / 2), imu[k + 1], k2);
    deriv(add(s, k2, h / 2), imu[k + 1], k3);
    deriv(add(s, k3, h), imu[k + 2], k4);
    s.q.coeffs() += h / 6 * (k1.q.coeffs() + 2 * k2.q.coeffs() + 2 * k3.q.coeffs() + k4.q.coeffs());
    s.q.normalize();
    s.v += h / 6 * (k1.v + 2 * k2.v + 2 * k3.v + k4.v);
    s.p += h / 6 * (k1.p + 2 * k2.p + 2 * k3.p + k4.p);
    const Pose& gt = truth[k + 2].T_world_imu;
    worst_p = std::max(worst_p, (s.p - gt.translation()).norm());
    worst_r = std::max(worst_r, rotationAngle(s.q.toRotationMatrix().transpose() * gt.linear()));
  }
  const double path = (truth.back().T_world_imu.translation() - truth.front().T_world_imu.translation()).norm();
  EXPECT_GT(path, 3.0);  // it did move
  EXPECT_LT(worst_p, 2e-4) << "position drift after " << imu.size() << " samples";
  EXPECT_LT(worst_r, 2e-5);
}

TEST(SimImu, NoiseAndBiasWalkMatchTheDensities) {
  SimScenario sc = makeScenario("room", "avia", true);
  sc.duration_s = 20.0;
  sc.imu.gyro_bias_init = {0.01, -0.02, 0.005};
  Simulator sim(sc);
  std::vector<ImuSample> imu;
  std::vector<ImuTruth> truth;
  sim.run({[&](const ImuSample& s, const ImuTruth& t) {
             imu.push_back(s);
             truth.push_back(t);
           },
           nullptr, nullptr});
  EXPECT_TRUE(truth[0].gyro_bias.isApprox(sc.imu.gyro_bias_init));
  const double n = static_cast<double>(imu.size());
  const double dt = 1.0 / sc.imu.rate_hz;
  for (int a = 0; a < 3; ++a) {
    double eg = 0, ea = 0, wg = 0, wa = 0;
    for (std::size_t k = 0; k < imu.size(); ++k) {
      eg += std::pow(imu[k].gyro[a] - truth[k].gyro[a] - truth[k].gyro_bias[a], 2);
      ea += std::pow(imu[k].accel[a] - truth[k].accel[a] - truth[k].accel_bias[a], 2);
      if (k + 1 < imu.size()) {
        wg += std::pow(truth[k + 1].gyro_bias[a] - truth[k].gyro_bias[a], 2);
        wa += std::pow(truth[k + 1].accel_bias[a] - truth[k].accel_bias[a], 2);
      }
    }
    // sigma_d = sigma_c sqrt(rate); walk step sigma_bw sqrt(dt). 4000 samples: 6% is ~5 standard errors.
    EXPECT_NEAR(std::sqrt(eg / n), sc.imu.gyro_noise / std::sqrt(dt), 0.06 * sc.imu.gyro_noise / std::sqrt(dt));
    EXPECT_NEAR(std::sqrt(ea / n), sc.imu.accel_noise / std::sqrt(dt), 0.06 * sc.imu.accel_noise / std::sqrt(dt));
    EXPECT_NEAR(std::sqrt(wg / (n - 1)), sc.imu.gyro_bias_walk * std::sqrt(dt), 0.06 * sc.imu.gyro_bias_walk * std::sqrt(dt));
    EXPECT_NEAR(std::sqrt(wa / (n - 1)), sc.imu.accel_bias_walk * std::sqrt(dt), 0.06 * sc.imu.accel_bias_walk * std::sqrt(dt));
  }
}

// ---------------------------------------------------------------- LiDAR

TEST(SimLidar, PointsLieOnTheSurfacesAtTheirOwnTimes) {
  for (const std::string model : {"avia", "mid360", "spinning32"}) {
    SCOPED_TRACE(model);
    SimScenario sc = makeScenario("room", model);
    sc.extrinsics.T_imu_lidar.translation() = Vec3(0.05, -0.02, 0.08);
    sc.extrinsics.T_imu_lidar.linear() = expSO3(Vec3(0.02, -0.03, 0.1));
    Simulator sim(sc);
    const std::int64_t j = 33;  // moving
    const LidarScan scan = sim.lidarScan(j);
    EXPECT_EQ(scan.utime, sim.startUtime() + 3'300'000);
    EXPECT_EQ(scan.sensor, model);
    const std::size_t rays = static_cast<std::size_t>(sim.lidarPattern().firingsPerScan()) * sim.lidarPattern().lasers();
    EXPECT_EQ(rays, model == "avia" ? 24000u : model == "mid360" ? 20000u : 32768u);
    EXPECT_GT(scan.points.size(), rays * 7 / 10);  // a closed room returns almost every ray
    const Pose T_start = sim.T_world_lidar(scan.utime);
    std::size_t checked = 0, off_with_start_pose = 0;
    for (std::size_t i = 0; i < scan.points.size(); i += 5) {
      const LidarPoint& p = scan.points[i];
      ASSERT_GE(p.time_offset_s, 0.f);
      ASSERT_LT(p.time_offset_s, 0.1f);
      ASSERT_GE(p.ring, 0);
      ASSERT_LT(p.ring, sim.lidarPattern().lasers());
      const double t = sim.relTime(scan.utime) + static_cast<double>(p.time_offset_s);
      const Pose T = sim.trajectory().pose(t) * sc.extrinsics.T_imu_lidar;
      const Vec3 p_world = T * p.p_lidar.cast<double>();
      ASSERT_LT(sim.world().distanceToSurface(p_world), 2e-5 * (1.0 + p.p_lidar.norm())) << "point " << i;
      off_with_start_pose += sim.world().distanceToSurface(T_start * p.p_lidar.cast<double>()) > 0.005;
      ++checked;
    }
    // Motion distortion is real: the scan-start pose puts many points off the surfaces.
    EXPECT_GT(off_with_start_pose, checked / 4);
  }
}

TEST(SimLidar, BlindMaxRangeAndGrazingReturnsAreDropped) {
  SimScenario sc = makeScenario("wall");
  // The sensor starts 0.8 m in front of the wall, facing it: a beam at angle a from the normal has
  // range 0.8 / cos(a). Blind 0.85 m drops a < 19.7 deg, incidence > 30 deg is grazing, max range
  // 0.95 m drops a > 32.6 deg (the Avia reaches 38.6 deg).
  sc.world.size_m = {0.8, 40.0, 20.0};
  sc.lidar.range_noise_m = 0.002;
  sc.lidar.blind_m = 0.85;
  sc.lidar.max_range_m = 0.95;
  sc.lidar.max_incidence_deg = 30.0;
  Simulator sim(sc);
  LidarStats st;
  const LidarScan scan = sim.lidarScan(0, &st);  // at rest
  ASSERT_GT(scan.points.size(), 100u);
  EXPECT_GT(st.blind, 1000u);
  EXPECT_GT(st.no_return, 200u);
  EXPECT_GT(st.grazing, 200u);
  EXPECT_EQ(st.points + st.blind + st.no_return + st.grazing, st.rays);
  for (const auto& p : scan.points) {
    const double r = p.p_lidar.norm();
    ASSERT_GE(r, sc.lidar.blind_m);
    ASSERT_LE(r, sc.lidar.max_range_m);
    // The wall normal is -x of the world; the sensor faces +x at rest (no beam noise here).
    const Vec3 dir_world = sim.T_world_lidar(scan.utime).linear() * p.p_lidar.cast<double>().normalized();
    ASSERT_GE(dir_world.x(), std::cos(30.0 * kPi / 180.0) - 1e-6);
  }
}

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

TEST(SimWorld, BvhRaycastMatchesBruteForce) {
  for (const std::string kind : {"room", "street"}) {
    SCOPED_TRACE(kind);
    const SimScenario sc = makeScenario(kind, kind == "street" ? "spinning32" : "avia");
    Simulator sim(sc);
    SplitMix rng(11);
    int hits = 0;
    for (int k = 0; k < 3000; ++k) {
      const auto& path = sim.trajectory().path();
      const Vec3 o = path[static_cast<std::size_t>(rng.next() % path.size())] + Vec3(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), 0.0);
      const Vec3 d = Vec3(rng.gaussian(), rng.gaussian(), rng.gaussian()).normalized();
      const Hit a = sim.world().raycast(o, d, 150.0), b = sim.world().raycastBruteForce(o, d, 150.0);
      ASSERT_EQ(a.valid, b.valid);
      if (!a.valid) continue;
      ++hits;
      ASSERT_EQ(a.surface, b.surface);
      ASSERT_EQ(a.distance, b.distance);
      ASSERT_EQ(a.albedo, b.albedo);
    }
    EXPECT_GT(hits, 1000);
  }
}

TEST(SimWorld, CorridorHasNoSurfaceAlongItsAxisWithinLidarRange) {
  const SimScenario sc = loadScenarioFile(std::string(LIVO_SOURCE_DIR) + "/config/sim/corridor.yaml");
  Simulator sim(sc);
  double x_min = 1e9, x_max = -1e9;
  std::size_t hits = 0;
  for (double t = 0.0; t <= sc.duration_s; t += 1.0) {
    const Pose T = sim.T_world_lidar(t0Utime(sim, t));
    x_min = std::min(x_min, T.translation().x());
    x_max = std::max(x_max, T.translation().x());
    const int n = 1500;  // Fibonacci sphere of directions
    for (int k = 0; k < n; ++k) {
      const double z = 1.0 - 2.0 * (k + 0.5) / n, r = std::sqrt(1.0 - z * z), phi = k * 2.399963229728653;
      const Hit h = sim.world().raycast(T.translation(), Vec3(r * std::cos(phi), r * std::sin(phi), z), sc.lidar.max_range_m);
      if (!h.valid) continue;
      ++hits;
      ASSERT_EQ(h.normal.x(), 0.0) << "surface " << h.surface << " at " << h.point.transpose();
    }
  }
  EXPECT_GT(hits, 50000u);
  EXPECT_GE(x_max - x_min, 60.0);  // the walk covers >= 60 m of corridor
}

// ---------------------------------------------------------------- events and determinism

TEST(SimEvents, TimeOrderedCompleteAndCameraIndependentOfScans) {
  SimScenario sc = makeScenario("room", "mid360", true);
  sc.duration_s = 1.0;
  Simulator sim(sc);
  SimEvent ev;
  Utime last = 0;
  int imu = 0, scans = 0, images = 0;
  while (sim.next(ev)) {
    ASSERT_GE(ev.utime, last);
    last = ev.utime;
    ASSERT_LT(ev.utime, sim.startUtime() + 1'000'000);
    if (ev.kind == SimEvent::Kind::Imu) {
      ++imu;
      ASSERT_EQ(ev.utime, ev.imu.utime);
    }
    if (ev.kind == SimEvent::Kind::Lidar) {
      ++scans;
      ASSERT_EQ(ev.utime, ev.scan.utime);
    }
    if (ev.kind == SimEvent::Kind::Image) {
      ++images;
      ASSERT_EQ(ev.utime, ev.image.utime);
      ASSERT_NE((ev.utime - sim.startUtime()) % 100'000, 0);  // not on a scan boundary
      ASSERT_EQ(ev.image.format, PixelFormat::Gray8);
      ASSERT_EQ(ev.image.data.size(), static_cast<std::size_t>(ev.image.width * ev.image.height));
    }
  }
  EXPECT_EQ(imu, 200);
  EXPECT_EQ(scans, 10);
  EXPECT_EQ(images, 10);
}

namespace {

// Every byte of every event of a run, in order.
std::vector<std::uint8_t> runBytes(SimScenario sc, int threads) {
  std::vector<std::uint8_t> out;
  auto put = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  Simulator sim(sc, SimOptions{threads});
  SimEvent ev;
  while (sim.next(ev)) {
    put(&ev.utime, sizeof ev.utime);
    if (ev.kind == SimEvent::Kind::Imu) put(ev.imu.gyro.data(), 24), put(ev.imu.accel.data(), 24);
    if (ev.kind == SimEvent::Kind::Lidar)
      for (const auto& p : ev.scan.points) put(p.p_lidar.data(), 12), put(&p.time_offset_s, 4), put(&p.intensity, 4), put(&p.ring, 2);
    if (ev.kind == SimEvent::Kind::Image) put(ev.image.data.data(), ev.image.data.size());
  }
  return out;
}

}  // namespace

TEST(SimDeterminism, SameSeedSameBytesWhateverTheThreadCount) {
  SimScenario sc = makeScenario("room", "avia", true);
  sc.duration_s = 1.2;
  const auto a = runBytes(sc, 1), b = runBytes(sc, 3);
  EXPECT_GT(a.size(), 1'000'000u);
  EXPECT_TRUE(a == b);
  sc.seed = 8;
  EXPECT_FALSE(a == runBytes(sc, 2));
}
