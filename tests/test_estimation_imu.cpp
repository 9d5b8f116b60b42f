// libs/estimation IMU: propagation (transition matrix vs numeric differences, exact motion, real EuRoC
// IMU vs ground truth), the start from the first window of samples, and the IMU config's checks.
// livo-test-deps: livo_eval
#include "livo/estimation/imu.hpp"
#include "livo/estimation/imu_init.hpp"
#include "livo/estimation/state.hpp"
#include "livo/eval/tum.hpp"

#include "estimation_test_util.hpp"
#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>

using namespace livo;
using livo_test::randomState;

// The error-state transition F must match numeric differences of the nominal propagation, entry by
// entry: column i of F is (propagate(x [+] eps e_i) [-] propagate(x [-] eps e_i)) / (2 eps) for one
// interval. Then the covariance recursion: with Q = 0 and P = I, propagate() gives exactly F F^T.
TEST(Imu, TransitionMatrixMatchesNumericDifferences) {
  std::mt19937 rng(2);
  ImuConfig quiet;
  quiet.gyro_noise = quiet.accel_noise = quiet.gyro_bias_walk = quiet.accel_bias_walk = 0;
  quiet.inv_exposure_walk = 0;
  for (const double accel_scale : {1.0, 9.81}) {  // m/s^2 and g-unit IMUs
    const ImuPropagator prop(quiet, accel_scale);
    const NavState x = randomState(rng);
    std::vector<ImuSample> samples(2);
    samples[0].utime = x.utime;
    samples[0].gyro = Vec3(0.3, -0.2, 0.5);
    samples[0].accel = Vec3(1.0, 0.5, 9.6) / accel_scale;
    samples[1] = samples[0];
    samples[1].utime = x.utime + 5000;  // one interval of 5 ms
    const Utime t_end = samples[1].utime;
    const double dt = 0.005;

    NavState base = x;
    StateCov unused = StateCov::Zero();
    prop.propagate(base, unused, samples, t_end, nullptr);
    const double eps = 1e-6;
    Eigen::Matrix<double, kStateDim, kStateDim> F_num;
    for (int i = 0; i < kStateDim; ++i) {
      StateVec d = StateVec::Zero();
      d[i] = eps;
      NavState xp = x.boxplus(d), xm = x.boxplus(-d);
      StateCov Pp = StateCov::Zero(), Pm = StateCov::Zero();
      prop.propagate(xp, Pp, samples, t_end, nullptr);
      prop.propagate(xm, Pm, samples, t_end, nullptr);
      F_num.col(i) = (xp.boxminus(base) - xm.boxminus(base)) / (2 * eps);
    }
    const StateCov F = prop.transition(x, samples[0].gyro, samples[0].accel, dt);
    // Central differences: truncation O(eps^2) and rounding ~1e-16 / eps per entry.
    for (int r = 0; r < kStateDim; ++r)
      for (int c = 0; c < kStateDim; ++c)
        EXPECT_NEAR(F(r, c), F_num(r, c), 1e-8) << "F(" << r << ", " << c << "), accel scale " << accel_scale;

    StateCov P = StateCov::Identity();
    NavState x0 = x;
    prop.propagate(x0, P, samples, t_end, nullptr);
    EXPECT_LT((P - F * F.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

// Exact motion: constant angular rate and constant world acceleration integrate in closed form.
TEST(Imu, PropagationOfExactConstantMotion) {
  ImuConfig cfg;
  const ImuPropagator prop(cfg, 1.0);
  NavState x;
  x.utime = 1000000;
  x.v_world = Vec3(1, 0, 0);
  const Vec3 w(0, 0, 0.5);            // yaw rate
  const Vec3 a_world(0.2, 0.1, 0.0);  // world acceleration
  // Samples at 200 Hz from the analytic motion: specific force f = R^T (a - g).
  std::vector<ImuSample> s;
  for (int k = 0; k <= 200; ++k) {
    const double t = k * 0.005;
    ImuSample m;
    m.utime = x.utime + fromSeconds(t);
    m.gyro = w;
    const Mat3 R = expSO3(w * t);
    m.accel = R.transpose() * (a_world - x.g_world);
    s.push_back(m);
  }
  StateCov P = initialCovariance();
  std::vector<ImuTracePoint> trace;
  prop.propagate(x, P, s, s.back().utime, &trace);
  const double T = 1.0;
  EXPECT_NEAR((x.p_world_imu - (Vec3(1, 0, 0) * T + 0.5 * a_world * T * T)).norm(), 0.0, 2e-4);
  EXPECT_NEAR((x.v_world - (Vec3(1, 0, 0) + a_world * T)).norm(), 0.0, 2e-3);
  EXPECT_NEAR(logSO3(x.R_world_imu.transpose() * expSO3(w * T)).norm(), 0.0, 1e-9);
  EXPECT_EQ(trace.size(), 201u);
  // The trace reproduces the pose in between samples.
  const Pose mid = ImuPropagator::poseAt(trace, s[0].utime + 502500);
  EXPECT_NEAR((mid.translation() - (Vec3(1, 0, 0) * 0.5025 + 0.5 * a_world * 0.5025 * 0.5025)).norm(), 0.0, 2e-4);
  EXPECT_TRUE(P.allFinite());
}

namespace {

/// A sample of an IMU at attitude R_world_imu accelerating at a_world (m/s^2, world frame), with white
/// noise of the given per-sample sigmas (rad/s, and m/s^2 before the unit scale `unit`) and a constant
/// gyro bias `bg`.
ImuSample imuSample(Utime t, const Mat3& R_world_imu, const Vec3& a_world, const Vec3& bg, double sigma_g,
                    double sigma_a, double unit, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  ImuSample s;
  s.utime = t;
  s.gyro = bg + sigma_g * Vec3(n(rng), n(rng), n(rng));
  s.accel = (R_world_imu.transpose() * (a_world + Vec3(0, 0, 9.81)) + sigma_a * Vec3(n(rng), n(rng), n(rng))) / unit;
  return s;
}

/// The same at rest.
ImuSample restingSample(Utime t, const Mat3& R_world_imu, const Vec3& bg, double sigma_g, double sigma_a, double unit,
                        std::mt19937& rng) {
  return imuSample(t, R_world_imu, Vec3::Zero(), bg, sigma_g, sigma_a, unit, rng);
}

/// The sample sigma of a configured density at 200 Hz.
double perSample(double density) { return density * std::sqrt(200.0); }


/// What ImuInitializer::start() gave.
struct Started {
  bool ok = false;
  NavState x;
  StateCov P = StateCov::Zero();
  double tilt_sigma = 0, scale = 0;
};

/// Feeds sample(k), k = 0, 1, ..., until the start is ready (at most 400), then starts; `fed` the count.
Started startFrom(ImuInitializer& init, const std::function<ImuSample(int)>& sample, int* fed = nullptr) {
  int k = 0;
  for (; k < 400 && !init.ready(); ++k) init.add(sample(k));
  if (fed) *fed = k;
  Started r;
  r.ok = init.start(r.x, r.P, r.tilt_sigma, r.scale);
  return r;
}

/// The angle between the start's gravity ("up" mapped to +z) and the true one.
double tiltError(const NavState& x, const Mat3& R_world_imu) {
  const Vec3 up_body = R_world_imu.transpose() * Vec3::UnitZ();
  return std::acos(std::clamp((x.R_world_imu * up_body).dot(Vec3::UnitZ()), -1.0, 1.0));
}

/// The start's tilt sigma as its covariance says (roll and pitch, world horizontal axes).
double tiltSigma(const NavState& x, const StateCov& P) {
  const Mat3 world = x.R_world_imu * P.block<3, 3>(sidx::kRot, sidx::kRot) * x.R_world_imu.transpose();
  return std::sqrt(world(0, 0));
}

}  // namespace

// The start needs one window of samples, whatever the rig does, and then reads what they observe: an
// IMU at rest in g units, tilted: the scale, gravity's direction within the noise of the window's mean,
// the gyro bias (the window's mean rate), and the priors the config sets.
TEST(Imu, StartFromTheFirstWindowDetectsGUnitsGravityAndBias) {
  ImuConfig cfg;  // 200 Hz, init_samples 30
  ImuInitializer init(cfg);
  EXPECT_NE(init.status().find("collecting the first 30 IMU samples"), std::string::npos) << init.status();
  std::mt19937 rng(4);
  const Mat3 R_world_imu = expSO3(Vec3(0.1, -0.2, 0.7));  // tilted IMU
  const Vec3 bg(0.01, -0.02, 0.005);
  int k = 0;
  const Started st = startFrom(
      init,
      [&](int i) {
        return restingSample(1000 + i * 5000, R_world_imu, bg, perSample(cfg.gyro_noise), perSample(cfg.accel_noise),
                             9.81, rng);  // Livox-like: g units
      },
      &k);
  EXPECT_EQ(k, cfg.init_samples) << "ready once the samples span one window";
  ASSERT_TRUE(st.ok);
  const NavState& x = st.x;
  const StateCov& P = st.P;
  const double tilt_sigma = st.tilt_sigma, scale = st.scale;
  const double n = double(cfg.init_samples);
  EXPECT_NEAR(scale, 9.81, 4 * perSample(cfg.accel_noise) / std::sqrt(n));  // the mean's noise along "up"
  EXPECT_LT((x.bg - bg).cwiseAbs().maxCoeff(), 4 * perSample(cfg.gyro_noise) / std::sqrt(n));
  EXPECT_LT(tiltError(x, R_world_imu), 4 * perSample(cfg.accel_noise) / (9.81 * std::sqrt(n)));
  EXPECT_NEAR((x.g_world - Vec3(0, 0, -9.81)).norm(), 0.0, 1e-9);
  // At rest the samples' spread (sqrt(3) sigma per sample over three axes) bounds the mean's error,
  // conservatively for white noise: at least the 2 degree floor.
  EXPECT_GE(tilt_sigma, 2.0 * M_PI / 180.0 - 1e-12);
  EXPECT_LE(tilt_sigma, std::atan2(1.2 * std::sqrt(3.0) * perSample(cfg.accel_noise), 9.81));
  EXPECT_NEAR(tiltSigma(x, P), tilt_sigma, 1e-9);
  EXPECT_NEAR(std::sqrt(P(sidx::kVel, sidx::kVel)), cfg.init_speed_sigma_mps, 1e-12);
  EXPECT_NEAR(std::sqrt(P(sidx::kBg, sidx::kBg)), cfg.init_gyro_bias_sigma_rad_s, 1e-12);
  EXPECT_NEAR(std::sqrt(P(sidx::kBa, sidx::kBa)), cfg.init_accel_bias_sigma_mps2, 1e-12);
  EXPECT_TRUE(P.allFinite());
  // A window whose specific force averages to zero gives no gravity: no start, and the wait says why.
  ImuInitializer falling(cfg);
  EXPECT_FALSE(startFrom(falling, [](int i) {
                 ImuSample z;
                 z.utime = i * 5000;
                 return z;
               }).ok);
  EXPECT_NE(falling.status().find("give no gravity"), std::string::npos) << falling.status();
}

// The tilt sigma covers what the window cannot tell from gravity: a car accelerating steadily at
// 0.5-3 m/s^2 (the mean is tilted by atan(a / g), 3-17 deg, with a calm spread), and rotor vibration
// of 3 m/s^2 at 91 Hz aliased by a 100 Hz IMU (a large spread, a mean close to gravity). A steady turn
// is calm too, but its mean rate is no gyro bias.
TEST(Imu, StartTiltSigmaCoversASteadyPushAndVibration) {
  const Mat3 R_world_imu = expSO3(Vec3(0.05, 0.1, -1.2));
  for (const double a : {0.5, 1.0, 2.0, 3.0}) {
    SCOPED_TRACE(a);
    ImuConfig cfg;  // m/s^2 IMU
    ImuInitializer init(cfg);
    std::mt19937 rng(7);
    const Started st = startFrom(init, [&](int k) {
      return imuSample(k * 5000, R_world_imu, Vec3(a * 0.6, a * 0.8, 0.0), Vec3::Zero(), 1e-3, perSample(cfg.accel_noise),
                       1.0, rng);
    });
    ASSERT_TRUE(st.ok);
    const double tilt_sigma = st.tilt_sigma;
    const double err = tiltError(st.x, R_world_imu);
    EXPECT_NEAR(err, std::atan2(a, 9.81), 0.01);
    // Covered where the clamp allows (17 deg at 3 m/s^2 is beyond the 15 deg cap: within 1.2 sigma).
    EXPECT_LE(err, 1.2 * tilt_sigma) << "tilt error " << err * 180 / M_PI << " deg, sigma " << tilt_sigma * 180 / M_PI;
    EXPECT_LE(tilt_sigma, 15.0 * M_PI / 180.0 + 1e-12);
  }
  {
    ImuConfig cfg;
    cfg.rate_hz = 100.0;
    ImuInitializer init(cfg);
    std::mt19937 rng(8);
    const Started st = startFrom(init, [&](int k) {
      const double t = k * 0.01;
      return imuSample(k * 10000, R_world_imu, Vec3(0, 0, 3.0 * std::sqrt(2.0) * std::sin(2 * M_PI * 91.0 * t)),
                       Vec3::Zero(), 1e-3, perSample(cfg.accel_noise), 1.0, rng);
    });
    ASSERT_TRUE(st.ok);
    EXPECT_LE(tiltError(st.x, R_world_imu), st.tilt_sigma);
    EXPECT_GT(st.tilt_sigma, 10.0 * M_PI / 180.0) << "an RMS of 3 m/s^2 says the mean may be off by about that much";
  }
  {
    ImuConfig cfg;
    ImuInitializer init(cfg);
    std::mt19937 rng(9);
    const Started st = startFrom(init, [&](int k) {
      return restingSample(k * 5000, Mat3::Identity(), Vec3(0, 0, 0.3), perSample(cfg.gyro_noise),
                           perSample(cfg.accel_noise), 1.0, rng);  // a steady turn of 0.3 rad/s
    });
    ASSERT_TRUE(st.ok);
    EXPECT_EQ(st.x.bg, Vec3::Zero()) << "0.3 rad/s is 15 prior sigmas: a turn, not a bias";
  }
}

// Real IMU: EuRoC V1_01 (ADIS16448, 200 Hz) propagated for 1 s from the ground-truth state stays
// within the drift expected from its noise.
TEST(Imu, EurocPropagationAgainstGroundTruth) {
  const std::string dir = std::string(LIVO_SHARED_DATA) + "/euroc_v1_01_micro";
  if (!std::filesystem::exists(dir)) LIVO_SKIP() << "no reference data at " << dir;
  const Trajectory gt = readTum(dir + "/groundtruth_V1_01_easy_200hz_tum.txt");
  std::ifstream in(dir + "/mav0/imu0/data.csv");
  std::string line;
  std::vector<ImuSample> imu;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ss(line);
    long long ns;
    ImuSample s;
    ss >> ns >> s.gyro.x() >> s.gyro.y() >> s.gyro.z() >> s.accel.x() >> s.accel.y() >> s.accel.z();
    s.utime = ns / 1000;
    imu.push_back(s);
  }
  ASSERT_GT(imu.size(), 1000u);
  // Start 20 s into the ground truth (moving); velocity by central difference of GT positions.
  const std::size_t k0 = 4000;
  ASSERT_LT(k0 + 201, gt.size());
  NavState x;
  x.utime = fromSeconds(gt[k0].t);
  x.R_world_imu = gt[k0].T_world_body.linear();
  x.p_world_imu = gt[k0].T_world_body.translation();
  x.v_world = (gt[k0 + 1].T_world_body.translation() - gt[k0 - 1].T_world_body.translation()) / (gt[k0 + 1].t - gt[k0 - 1].t);
  // Gyro bias calibrated on the 2 s before the test window: mean gyro minus the ground truth's mean
  // body rate (log of consecutive relative rotations). The test window itself is never used for it.
  // The accelerometer bias likewise: mean specific force minus R^T (a - g) with a from second
  // differences of the ground-truth positions.
  x.g_world = Vec3(0, 0, -9.81);
  Vec3 w_gt = Vec3::Zero(), w_imu = Vec3::Zero(), f_gt = Vec3::Zero(), f_imu = Vec3::Zero();
  int nw = 0, ni = 0;
  for (std::size_t k = k0 - 400; k < k0; ++k) {
    const double dt = gt[k + 1].t - gt[k].t;
    w_gt += logSO3(gt[k].T_world_body.linear().transpose() * gt[k + 1].T_world_body.linear()) / dt;
    const Vec3 a = (gt[k + 1].T_world_body.translation() - 2 * gt[k].T_world_body.translation() +
                    gt[k - 1].T_world_body.translation()) / (dt * dt);
    f_gt += gt[k].T_world_body.linear().transpose() * (a - x.g_world);
    ++nw;
  }
  for (const auto& s : imu)
    if (s.utime >= fromSeconds(gt[k0 - 400].t) && s.utime < fromSeconds(gt[k0].t)) {
      w_imu += s.gyro;
      f_imu += s.accel;
      ++ni;
    }
  ASSERT_GT(ni, 300);
  x.bg = w_imu / ni - w_gt / nw;
  x.ba = f_imu / ni - f_gt / nw;
  std::vector<ImuSample> window;
  for (const auto& s : imu)
    if (s.utime >= x.utime - 10000 && s.utime <= x.utime + 1010000) window.push_back(s);
  ImuConfig cfg;
  const ImuPropagator prop(cfg, 1.0);
  StateCov P = initialCovariance();
  const Utime t_end = fromSeconds(gt[k0 + 200].t);
  prop.propagate(x, P, window, t_end, nullptr);
  const double pos_err = (x.p_world_imu - gt[k0 + 200].T_world_body.translation()).norm();
  const double rot_err = rotationAngle(x.R_world_imu.transpose() * gt[k0 + 200].T_world_body.linear());
  EXPECT_LT(pos_err, 0.05) << "1 s of real IMU integration";
  EXPECT_LT(rot_err, 0.3 * M_PI / 180.0) << "gyro bias calibrated on the previous 2 s";
}

namespace {
std::string imuConfigError(const std::string& yaml) {
  auto f = livo::ConfigFile::parse(yaml, "rig.yaml");
  livo::ImuConfig c;
  try {
    c.load(f.root().section("imu"), 200.0);
  } catch (const livo::ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ImuConfig, RefusesZeroOrAbsurdDensitiesAndTheRemovedKey) {
  EXPECT_EQ(imuConfigError("imu:\n  gyro_noise: 1.0e-3\n"), "");
  EXPECT_NE(imuConfigError("imu:\n  gyro_noise: 0\n").find("imu.gyro_noise: must be > 0"), std::string::npos);
  // 5 deg/s/sqrt(Hz) typed in a rad key: no real IMU is that noisy.
  EXPECT_NE(imuConfigError("imu:\n  accel_noise: 20\n").find("imu.accel_noise"), std::string::npos);
  const std::string removed = imuConfigError("imu:\n  init_max_samples: 2000\n");
  EXPECT_NE(removed.find("imu.init_max_samples"), std::string::npos) << removed;
  EXPECT_NE(imuConfigError("imu:\n  init_speed_sigma_mps: 0\n").find("imu.init_speed_sigma_mps"), std::string::npos);
}

// The keys of the start's removed rules (static test, motion initialiser, deadline) still load: read,
// ignored and listed for the start's message; an unknown key stays unknown (ConfigFile's check).
TEST(ImuConfig, TheRemovedStartRulesKeysAreReadAndNamed) {
  auto f = livo::ConfigFile::parse("imu:\n  init_static_wait_s: 1.0\n  start: rules\n  init_motion_max_speed_mps: 15\n",
                                   "rig.yaml");
  livo::ImuConfig c;
  c.load(f.root().section("imu"), 200.0);
  EXPECT_EQ(c.ignored_keys, (std::vector<std::string>{"imu.init_static_wait_s", "imu.start", "imu.init_motion_max_speed_mps"}));
  EXPECT_TRUE(f.unusedKeys().empty());
}
