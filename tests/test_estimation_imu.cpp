// libs/estimation IMU: propagation (transition matrix vs numeric differences, exact motion, real EuRoC
// IMU vs ground truth), static initialisation from the configured noise, and the IMU config's checks.
// livo-test-deps: livo_eval
#include "livo/estimation/imu.hpp"
#include "livo/estimation/imu_init.hpp"
#include "livo/estimation/state.hpp"
#include "livo/eval/tum.hpp"

#include "estimation_test_util.hpp"
#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
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

/// A sample of an IMU at rest at attitude R_world_imu with white noise of the given per-sample sigmas
/// (rad/s, and m/s^2 before the unit scale `unit`), constant gyro bias `bg`.
ImuSample restingSample(Utime t, const Mat3& R_world_imu, const Vec3& bg, double sigma_g, double sigma_a, double unit,
                        std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  const Vec3 up_body = R_world_imu.transpose() * Vec3::UnitZ();
  ImuSample s;
  s.utime = t;
  s.gyro = bg + sigma_g * Vec3(n(rng), n(rng), n(rng));
  s.accel = (up_body * 9.81 + sigma_a * Vec3(n(rng), n(rng), n(rng))) / unit;
  return s;
}

/// The sample sigma of a configured density at 200 Hz.
double perSample(double density) { return density * std::sqrt(200.0); }

}  // namespace

TEST(Imu, StaticInitialisationDetectsGUnitsAndBias) {
  ImuConfig cfg;  // 200 Hz, init_static_wait_s 1
  ImuInitializer init(cfg);
  std::mt19937 rng(4);
  const Mat3 R_world_imu = expSO3(Vec3(0.1, -0.2, 0.7));  // tilted IMU
  const Vec3 bg(0.01, -0.02, 0.005);
  int k = 0;
  for (; k < 400 && !init.done(); ++k)
    init.add(restingSample(1000 + k * 5000, R_world_imu, bg, perSample(cfg.gyro_noise), perSample(cfg.accel_noise),
                           9.81, rng));  // Livox-like: g units
  ASSERT_TRUE(init.done());
  EXPECT_EQ(k, 201) << "decided when the wait (1 s after the first sample) is over";
  EXPECT_NEAR(init.accelScale(), 9.81, 0.05);
  const NavState x0 = init.initialState();
  // The gyro bias is the window mean: within 4 sigma of sigma_gyro / sqrt(n) per axis.
  const double sigma_bg = perSample(cfg.gyro_noise) / std::sqrt(double(cfg.init_samples));
  EXPECT_LT((x0.bg - bg).cwiseAbs().maxCoeff(), 4 * sigma_bg);
  const StateCov P = init.initialCovariance();
  EXPECT_NEAR(std::sqrt(P(sidx::kBg, sidx::kBg)), sigma_bg, 0.05 * sigma_bg) << "the prior says what was observed";
  // Gravity aligned: the measured up direction maps to world +z.
  const Vec3 up_body = R_world_imu.transpose() * Vec3::UnitZ();
  const double sigma_tilt = perSample(cfg.accel_noise) / (9.81 * std::sqrt(double(cfg.init_samples)));
  EXPECT_NEAR((x0.R_world_imu * up_body - Vec3::UnitZ()).norm(), 0.0, 4 * sigma_tilt);
  EXPECT_NEAR((x0.g_world - Vec3(0, 0, -9.81)).norm(), 0.0, 1e-9);
}

// The static test follows the configured noise: a consumer-grade IMU (10x the densities) at rest
// passes when its config says so, and fails when the config claims the quiet IMU; a rotating IMU
// never passes, however long it runs.
TEST(Imu, StaticTestThresholdsFollowTheConfiguredNoise) {
  ImuConfig quiet;
  ImuConfig noisy = quiet;
  noisy.gyro_noise *= 10;
  noisy.accel_noise *= 10;
  EXPECT_NEAR(noisy.staticGyroThreshold() / quiet.staticGyroThreshold(), 10.0, 1e-9);
  const auto feed = [](ImuInitializer& init, const ImuConfig& truth, int n, bool rotating, std::mt19937& rng) {
    for (int k = 0; k < n && !init.done(); ++k) {
      ImuSample s = restingSample(k * 5000, Mat3::Identity(), Vec3::Zero(), perSample(truth.gyro_noise),
                                  perSample(truth.accel_noise), 1.0, rng);
      if (rotating) s.gyro.x() += 3.0 * std::sin(k * 0.2);  // a hand shaking the rig at 6 Hz
      init.add(s);
    }
  };
  std::mt19937 rng(11);
  ImuInitializer right(noisy);
  feed(right, noisy, 400, false, rng);
  EXPECT_TRUE(right.done()) << "consumer IMU at rest, configured as such";
  ImuInitializer wrong(quiet);
  feed(wrong, noisy, 400, false, rng);
  EXPECT_FALSE(wrong.done()) << "10x the configured noise is not rest";
  EXPECT_TRUE(wrong.noStaticWindow());
  ImuInitializer moving(noisy);
  feed(moving, noisy, 2000, true, rng);
  ImuInitializer turning(quiet);  // a steady turn is calm, but its mean rate is no gyro bias
  for (int k = 0; k < 400; ++k) {
    ImuSample s = restingSample(k * 5000, Mat3::Identity(), Vec3::Zero(), perSample(quiet.gyro_noise),
                                perSample(quiet.accel_noise), 1.0, rng);
    s.gyro.z() += 0.3;
    turning.add(s);
  }
  EXPECT_FALSE(turning.done());
  EXPECT_FALSE(moving.done()) << "a window in motion is never used";
  EXPECT_TRUE(moving.noStaticWindow());
}

// Of the static windows, the calmest is used: half a second of rest under vibration close to the
// margin, then calm rest with another gyro bias (e.g. a motor switched off): the bias of the calm part.
TEST(Imu, TheCalmestStaticWindowIsUsed) {
  ImuConfig cfg;
  cfg.init_vibration_gyro_rad_s = 0.2;  // the rig's documented vibration at rest
  ImuInitializer init(cfg);
  std::mt19937 rng(5);
  const Vec3 bg_vibrating(0.05, 0.0, 0.0), bg_calm(0.01, -0.02, 0.0);
  int k = 0;
  for (; k < 400 && !init.done(); ++k) {
    const bool vibrating = k < 100;
    init.add(restingSample(k * 5000, Mat3::Identity(), vibrating ? bg_vibrating : bg_calm,
                           vibrating ? 0.08 : perSample(cfg.gyro_noise), perSample(cfg.accel_noise), 1.0, rng));
  }
  ASSERT_TRUE(init.done());
  const double sigma_bg = perSample(cfg.gyro_noise) / std::sqrt(double(cfg.init_samples));
  EXPECT_LT((init.initialState().bg - bg_calm).cwiseAbs().maxCoeff(), 4 * sigma_bg) << init.describe();
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
  EXPECT_NE(removed.find("init_static_wait_s"), std::string::npos) << removed;
}
