// libs/sim against its own ground truth: trajectory derivatives vs finite differences, IMU integrated
// back to the trajectory (RK4), noise statistics vs the configured densities, vibration aliased by the
// sampling.
#include "sim_test_util.hpp"

#include "livo/sim/random.hpp"
#include "livo/sim/simulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

using namespace livo;
using namespace livo::sim;
using namespace livo::sim::test;

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

// A start in motion (static_s = ramp_s = 0) is at cruise from its first instant: the state at t = 0 is
// the limit of the states after it (the first IMU sample does not read rest).
TEST(SimTrajectory, AStartInMotionMovesAtItsFirstInstant) {
  SimScenario sc = makeScenario("street");
  sc.trajectory.static_s = sc.trajectory.ramp_s = 0.0;
  sc.trajectory.start_m = 60.0;  // on the first straight (125 m)
  const SimTrajectory tr(sc.trajectory, sc.world);
  const BodyState s0 = tr.state(0.0), s1 = tr.state(1e-7);
  EXPECT_GT(s0.v_world.norm(), 0.9 * sc.trajectory.speed_mps);
  EXPECT_LT((s0.v_world - s1.v_world).norm(), 1e-5);
  EXPECT_LT((s0.a_world - s1.a_world).norm(), 1e-4);
  EXPECT_LT((s0.omega_body - s1.omega_body).norm(), 1e-5);
  // In a turn too (an oval room loop: always turning).
  SimScenario room = makeScenario("room");
  room.trajectory.static_s = room.trajectory.ramp_s = 0.0;
  const SimTrajectory tr2(room.trajectory, room.world);
  const BodyState r0 = tr2.state(0.0), r1 = tr2.state(1e-7);
  EXPECT_GT(r0.omega_body.norm(), 0.05);
  EXPECT_LT((r0.omega_body - r1.omega_body).norm(), 1e-5);
  EXPECT_LT((r0.a_world - r1.a_world).norm(), 1e-4);
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

// Vibration is a signal evaluated at the IMU's sample times (a sampling IMU without an anti-aliasing
// filter): 91 Hz sampled at 100 Hz shows as a 9 Hz oscillation. Oracle from the vibration model
// (scenario.hpp): per axis a centre tone at freq_hz with half of the power plus side tones (84.6, 94.6
// and 100.1 Hz: aliased to 15.4, 5.4 and 0.1 Hz), the RMS being the configured amplitude; so the
// samples oscillate at |91 - 100| = 9 Hz with amplitude sqrt(2 x 0.5) x RMS = RMS and keep the RMS.
TEST(SimImu, VibrationAboveNyquistAliasesAtItsAmplitude) {
  SimScenario sc = makeScenario("room");  // noise-free
  sc.seed = 11;
  sc.duration_s = 20.0;  // 2000 samples: 9 Hz is bin 180 exactly
  sc.trajectory.static_s = 30.0;  // at rest throughout
  sc.imu.rate_hz = 100.0;
  sc.imu.vibration.accel_mps2 = 1.5;
  sc.imu.vibration.gyro_rad_s = 0.04;
  sc.imu.vibration.freq_hz = 91.0;
  Simulator sim(sc);
  std::vector<Vec3> dg, da;  // measurement - truth: the vibration alone
  sim.run({[&](const ImuSample& s, const ImuTruth& t) {
             dg.push_back(s.gyro - t.gyro);
             da.push_back(s.accel - t.accel);
           },
           nullptr, nullptr});
  ASSERT_EQ(dg.size(), 2000u);
  const double n = static_cast<double>(dg.size());
  // Amplitude of the component at f Hz in samples at 100 Hz (DFT; f on a bin of the 20 s window).
  auto amplitude = [&](const std::vector<Vec3>& x, int axis, double f) {
    double re = 0.0, im = 0.0;
    for (std::size_t k = 0; k < x.size(); ++k) {
      const double ph = 2.0 * kPi * f * static_cast<double>(k) / sc.imu.rate_hz;
      re += x[k][axis] * std::cos(ph);
      im -= x[k][axis] * std::sin(ph);
    }
    return 2.0 / n * std::hypot(re, im);
  };
  for (int a = 0; a < 3; ++a) {
    SCOPED_TRACE(a);
    for (const auto& [x, rms] : {std::make_pair(&dg, sc.imu.vibration.gyro_rad_s), std::make_pair(&da, sc.imu.vibration.accel_mps2)}) {
      EXPECT_NEAR(amplitude(*x, a, 9.0), rms, 0.03 * rms) << "the 91 Hz tone seen at 9 Hz";
      EXPECT_LT(amplitude(*x, a, 30.0), 0.02 * rms) << "nothing where no tone aliases (not a white noise)";
      double sq = 0.0;
      for (const Vec3& v : *x) sq += v[a] * v[a];
      EXPECT_NEAR(std::sqrt(sq / n), rms, 0.03 * rms) << "the RMS survives the sampling";
    }
  }
}

// imu.fault_s + fault_accel_mps2: inside the interval the accelerometer reads the jump more (body frame)
// and the ground truth's accel bias says so; outside, the samples are the fault-free ones.
TEST(SimImu, AnAccelerometerFaultComesAndGoes) {
  SimScenario sc = makeScenario("room");
  sc.duration_s = 3.0;
  const auto samples = [](const SimScenario& s) {
    std::vector<std::pair<ImuSample, ImuTruth>> out;
    Simulator sim(s);
    sim.run({[&](const ImuSample& m, const ImuTruth& t) { out.emplace_back(m, t); }, nullptr, nullptr});
    return out;
  };
  const auto clean = samples(sc);
  sc.imu.fault_s = {1.0, 1.5};
  sc.imu.fault_accel_mps2 = Vec3(4.0, 0.0, -1.0);
  const auto faulty = samples(sc);
  ASSERT_EQ(clean.size(), faulty.size());
  std::size_t inside = 0;
  for (std::size_t k = 0; k < clean.size(); ++k) {
    const double t = toSeconds(clean[k].first.utime - clean.front().first.utime);
    const Vec3 d = faulty[k].first.accel - clean[k].first.accel;
    const bool in = t >= 1.0 && t < 1.5;
    inside += in;
    EXPECT_NEAR((d - (in ? sc.imu.fault_accel_mps2 : Vec3::Zero())).norm(), 0.0, 1e-9) << t;
    EXPECT_NEAR((faulty[k].second.accel_bias - clean[k].second.accel_bias - (in ? sc.imu.fault_accel_mps2 : Vec3::Zero())).norm(), 0.0, 1e-12);
    EXPECT_EQ(faulty[k].first.gyro, clean[k].first.gyro);
  }
  EXPECT_EQ(inside, 100u);  // 0.5 s at 200 Hz
}
