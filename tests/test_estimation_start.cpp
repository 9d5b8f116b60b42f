// libs/estimation FilterStart (filter_start.hpp): the start's prior from the first IMU samples.
// Oracle: samples synthesised from a known attitude and motion; the prior must contain the truth
// within the sigmas it reports (honest), stay tight where the data are calm, and never depend on
// whether the rig rests. The start's registration is exercised end to end in test_pipeline_start.cpp.
#include "livo/estimation/filter_start.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

using namespace livo;

namespace {

constexpr double kG = 9.81;
constexpr double kRate = 200.0;

/// Specific-force and rate of a motion: world acceleration a(t) and body attitude R(t), body rate w(t).
struct Motion {
  std::function<Vec3(double)> accel_world = [](double) { return Vec3::Zero(); };
  std::function<Mat3(double)> R_world_imu = [](double) { return Mat3::Identity(); };
  std::function<Vec3(double)> rate_body = [](double) { return Vec3::Zero(); };
  std::function<Vec3(double)> vibration = [](double) { return Vec3::Zero(); };  ///< added to the accelerometer
};

/// A frame of samples at `rate` over [t0, t1] with white noise of the configured densities, in `unit`.
Frame frameOf(const Motion& m, double t0, double t1, double rate, const ImuConfig& cfg, double unit, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Frame f;
  f.utime = fromSeconds(t1);
  f.sweep_start_utime = fromSeconds(t0);
  const double sg = cfg.gyro_noise * std::sqrt(rate), sa = cfg.accel_noise * std::sqrt(rate);
  for (long k = std::lround(std::ceil(t0 * rate)); double(k) / rate <= t1 + 1e-9; ++k) {
    const double t = double(k) / rate;
    ImuSample s;
    s.utime = fromSeconds(t);
    s.gyro = m.rate_body(t) + sg * Vec3(n(rng), n(rng), n(rng));
    const Vec3 f_body = m.R_world_imu(t).transpose() * (m.accel_world(t) - Vec3(0, 0, -kG));
    s.accel = (f_body + m.vibration(t) + sa * Vec3(n(rng), n(rng), n(rng))) / unit;
    f.imu.push_back(s);
  }
  return f;
}

struct PriorCheck {
  NavState x;
  StateCov P;
  double accel_scale = 0;
  double sigma_h = 0;        ///< reported horizontal gravity sigma, m/s^2
  double err_h = 0;          ///< the truth's horizontal gravity in the start's world frame, m/s^2
};

/// Runs the start's prior on the motion from t = 0.5 s (frames of 0.1 s) until it starts.
PriorCheck priorOf(const Motion& m, ImuConfig cfg, double unit = 1.0, unsigned seed = 1, double rate = kRate) {
  cfg.rate_hz = rate;
  FilterStart start(cfg, StartConfig{}, VoxelMapConfig{}, LioConfig{}, 20, Pose::Identity());
  std::mt19937 rng(seed);
  PriorCheck c;
  for (int k = 0; k < 50; ++k) {
    const double t0 = 0.5 + 0.1 * k;
    const Frame f = frameOf(m, t0, t0 + 0.1, rate, cfg, unit, rng);
    if (!start.prior(f, c.x, c.P, c.accel_scale)) continue;
    // Gravity of the true world seen in the start's world: through the body at the state's time.
    const Mat3 R_true = m.R_world_imu(toSeconds(c.x.utime));
    const Vec3 g_start = c.x.R_world_imu * R_true.transpose() * Vec3(0, 0, -kG);
    c.err_h = (g_start - c.x.g_world).head<2>().norm();
    c.sigma_h = std::sqrt(c.P(sidx::kGrav, sidx::kGrav));
    EXPECT_NEAR(c.P(sidx::kGrav, sidx::kGrav), c.P(sidx::kGrav + 1, sidx::kGrav + 1), 1e-12);
    return c;
  }
  ADD_FAILURE() << "the start never began";
  return c;
}

}  // namespace

// A tilted IMU at rest reporting g units: the units are found, up maps to +z, the gravity sigma is
// what the samples and the accelerometer bias prior leave (a fraction of a degree), the velocity prior
// is the configured speed limit's (the IMU alone says nothing about constant velocity), the biases
// keep their priors, and the world's origin and attitude are the start's definition.
TEST(FilterStart, AtRestTiltedInGUnits) {
  ImuConfig cfg;
  Motion m;
  const Mat3 R = expSO3(Vec3(0.3, -0.2, 0.9));
  m.R_world_imu = [R](double) { return R; };
  const PriorCheck c = priorOf(m, cfg, kG);
  EXPECT_DOUBLE_EQ(c.accel_scale, kG);
  EXPECT_LT(c.err_h, 3.0 * c.sigma_h);
  EXPECT_LT(std::atan2(c.sigma_h, kG) * 180 / M_PI, 0.5) << "calm data: a tight prior";
  EXPECT_LT((c.x.g_world - Vec3(0, 0, -kG)).norm(), 1e-12);
  const StartConfig sc;
  EXPECT_NEAR(std::sqrt(c.P(sidx::kVel, sidx::kVel)), 0.5 * sc.max_speed_mps, 1e-9);
  EXPECT_NEAR(std::sqrt(c.P(sidx::kBg, sidx::kBg)), cfg.init_gyro_bias_sigma_rad_s, 1e-12);
  EXPECT_LT(c.P.block<6, 6>(0, 0).norm(), 1e-6);
  EXPECT_EQ(c.x.v_world, Vec3::Zero());
}

// The prior is honest whatever the rig does during its first samples: the truth's gravity direction
// lies within 3 reported sigmas under a car's constant acceleration (17 deg of apparent tilt), rotor
// vibration aliased by the IMU rate (2 m/s^2 at 91 Hz sampled at 100 Hz: a 9 Hz swing), a hand
// shaking the rig, and a steady turn (the gyro carries the samples into one body frame). Each case
// over several seeds; none is a special case of the code.
TEST(FilterStart, GravitySigmaContainsTheTruthUnderMotionAndVibration) {
  ImuConfig cfg;
  struct Case {
    const char* name;
    Motion m;
    double rate;
  };
  std::vector<Case> cases;
  {
    Motion m;  // a car accelerating at 3 m/s^2 along its heading
    const Mat3 R = expSO3(Vec3(0, 0, 0.7));
    m.R_world_imu = [R](double) { return R; };
    m.accel_world = [R](double) { return Vec3(R * Vec3(3.0, 0, 0)); };
    cases.push_back({"constant acceleration", m, 200.0});
  }
  {
    Motion m;  // rotor vibration above the Nyquist rate of a 100 Hz IMU
    m.vibration = [](double t) {
      return Vec3(2.0 * std::sin(2 * M_PI * 91.0 * t), 1.5 * std::sin(2 * M_PI * 91.0 * t + 1.0),
                  2.0 * std::sin(2 * M_PI * 91.0 * t + 2.0));
    };
    m.rate_body = [](double t) { return Vec3(0.05 * std::sin(2 * M_PI * 91.0 * t), 0, 0); };
    cases.push_back({"aliased vibration", m, 100.0});
  }
  {
    Motion m;  // a hand shaking the rig: 0.3 rad at 2 Hz about x, and 2 m/s^2 sideways at 3 Hz
    m.R_world_imu = [](double t) { return expSO3(Vec3(0.3 * std::sin(2 * M_PI * 2.0 * t), 0, 0)); };
    m.rate_body = [](double t) { return Vec3(0.3 * 2 * M_PI * 2.0 * std::cos(2 * M_PI * 2.0 * t), 0, 0); };
    m.accel_world = [](double t) { return Vec3(0, 2.0 * std::sin(2 * M_PI * 3.0 * t), 0); };
    cases.push_back({"shaking hand", m, 200.0});
  }
  {
    Motion m;  // turning at 1 rad/s about a tilted axis, no translation
    const Vec3 w(0.6, 0.0, 0.8);
    m.R_world_imu = [w](double t) { return expSO3(w * t); };
    m.rate_body = [w](double) { return w; };
    cases.push_back({"steady turn", m, 400.0});
  }
  for (const Case& c : cases)
    for (unsigned seed = 1; seed <= 5; ++seed) {
      const PriorCheck p = priorOf(c.m, cfg, 1.0, seed, c.rate);
      EXPECT_LT(p.err_h, 3.0 * p.sigma_h) << c.name << " seed " << seed << ": error " << p.err_h << " m/s^2, sigma "
                                          << p.sigma_h;
      EXPECT_DOUBLE_EQ(p.accel_scale, 1.0);
    }
  // The turn and the calm rest are not inflated by the rule: the steady turn's samples, rotated by the
  // gyro, are as calm as rest.
  const PriorCheck turn = priorOf(cases.back().m, cfg, 1.0, 3, 400.0);
  EXPECT_LT(std::atan2(turn.sigma_h, kG) * 180 / M_PI, 1.0);
}

// Too few samples: no start and no pose; the first frame with init_samples behind it starts, and the
// state is at that frame's first sample (its sweep is propagated through).
TEST(FilterStart, WaitsForInitSamplesAndStartsAtTheFrame) {
  ImuConfig cfg;
  cfg.init_samples = 50;  // 0.25 s at 200 Hz
  cfg.rate_hz = kRate;
  FilterStart start(cfg, StartConfig{}, VoxelMapConfig{}, LioConfig{}, 20, Pose::Identity());
  std::mt19937 rng(2);
  NavState x;
  StateCov P;
  double s = 0;
  const Motion m;
  EXPECT_FALSE(start.prior(frameOf(m, 0.0, 0.1, kRate, cfg, 1.0, rng), x, P, s));
  EXPECT_FALSE(start.prior(frameOf(m, 0.1, 0.2, kRate, cfg, 1.0, rng), x, P, s));
  const Frame third = frameOf(m, 0.2, 0.3, kRate, cfg, 1.0, rng);
  ASSERT_TRUE(start.prior(third, x, P, s));
  EXPECT_EQ(x.utime, third.imu.front().utime);
  EXPECT_NE(start.describe().find("filter started at once"), std::string::npos) << start.describe();
  // No gravity at all (an accelerometer reporting zeros): no start, however long.
  FilterStart none(cfg, StartConfig{}, VoxelMapConfig{}, LioConfig{}, 20, Pose::Identity());
  Frame zero = frameOf(m, 0.0, 1.0, kRate, cfg, 1.0, rng);
  for (auto& smp : zero.imu) smp.accel.setZero();
  EXPECT_FALSE(none.prior(zero, x, P, s));
}

TEST(StartConfig, RefusesAbsurdLimits) {
  const auto error = [](const std::string& yaml) -> std::string {
    auto f = ConfigFile::parse(yaml, "rig.yaml");
    StartConfig c;
    try {
      c.load(f.root().section("imu"));
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error("imu:\n  init_max_speed_mps: 30\n"), "");
  EXPECT_NE(error("imu:\n  init_max_speed_mps: 0\n").find("imu.init_max_speed_mps"), std::string::npos);
  EXPECT_NE(error("imu:\n  init_max_tilt_deg: 90\n").find("imu.init_max_tilt_deg"), std::string::npos);
}
