// libs/estimation IMU: propagation (transition matrix vs numeric differences, exact motion, real EuRoC
// IMU vs ground truth) and the IMU config's checks. The filter's start is in test_estimation_start.cpp.
// livo-test-deps: livo_eval
#include "livo/estimation/imu.hpp"
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
  EXPECT_NE(removed.find("init_samples"), std::string::npos) << removed;
  // The start's tree of rules is gone (issue 41): its keys say so and what replaced them.
  for (const char* key : {"init_static_wait_s: 1.0", "init_deadline_s: 1.5", "init_vibration_accel_mps2: 0.1",
                          "init_motion_min_updates: 5"}) {
    const std::string e = imuConfigError(std::string("imu:\n  ") + key + "\n");
    EXPECT_NE(e.find("was removed (issue 41)"), std::string::npos) << key << ": " << e;
  }
  EXPECT_NE(imuConfigError("imu:\n  init_motion_max_speed_mps: 10\n").find("renamed init_max_speed_mps"), std::string::npos);
}
