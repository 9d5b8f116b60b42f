// libs/estimation health.hpp: the frame's state from the filter's consistency checks (the LiDAR's
// correction against the IMU's prediction, the match share of the covered points, the speed), the
// persistence rule that turns inconsistent frames into a lost span, and the state after it. The
// statistic itself (the correction's chi-square) is checked against drawn priors in test_estimation.cpp.
#include "livo/estimation/health.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

using namespace livo;

namespace {

constexpr Utime kSecond = 1'000'000;

/// A frame at `t` (s) whose LiDAR update matched 950 of 1000 covered points with a correction of chi2 2.
HealthInputs consistent(double t) {
  HealthInputs in;
  in.utime = Utime(t * kSecond);
  in.initialized = true;
  in.update_ran = true;
  in.n_matched = 950;
  in.n_covered = 1000;
  in.correction_chi2 = 2.0;
  in.speed_mps = 1.0;
  return in;
}

/// The LiDAR moved the pose 30 cm where the IMU's prediction admitted a few (chi2 200).
HealthInputs inconsistent(double t) {
  HealthInputs in = consistent(t);
  in.correction_chi2 = 200.0;
  in.correction_m = 0.3;
  return in;
}

}  // namespace

TEST(Health, ConsistentFramesAreOkAndAFrameWithoutAPoseIsInitialising) {
  HealthMonitor m;
  HealthInputs wait = consistent(0.0);
  wait.initialized = false;
  EXPECT_EQ(m.assess(wait).state, HealthState::Initialising);
  for (int k = 1; k <= 50; ++k) {
    const FrameHealth h = m.assess(consistent(0.1 * k));
    EXPECT_EQ(h.state, HealthState::Ok) << h.reason;
    EXPECT_TRUE(h.reason.empty());
  }
  EXPECT_STREQ(healthName(HealthState::Lost), "lost");
}

TEST(Health, EachCheckOutOfItsBoundDegradesTheFrameAndSaysWhy) {
  HealthMonitor m;
  // The correction's chi-square above its bound (6 degrees of freedom, 0.1 %).
  FrameHealth h = m.assess(inconsistent(0.1));
  EXPECT_EQ(h.state, HealthState::Degraded);
  EXPECT_TRUE(h.inconsistent);
  EXPECT_NE(h.reason.find("correction chi2 200"), std::string::npos) << h.reason;
  // A scan that fits where the map has no planes (new ground) is no inconsistency ...
  HealthInputs fresh = consistent(0.2);
  fresh.n_covered = 10;
  fresh.n_matched = 2;
  EXPECT_EQ(m.assess(fresh).state, HealthState::Ok);
  // ... one that does not fit where it has them is: a share below half of its median over the
  // consistent frames before (0.95 here).
  for (int k = 1; k <= 5; ++k) EXPECT_EQ(m.assess(consistent(0.2 + 0.01 * k)).state, HealthState::Ok);
  HealthInputs misfit = consistent(0.3);
  misfit.n_matched = 400;
  h = m.assess(misfit);
  EXPECT_EQ(h.state, HealthState::Degraded);
  EXPECT_NE(h.reason.find("matched 400 of 1000 covered points (usually 0.95)"), std::string::npos) << h.reason;
  // A map whose share is low all along (a young map) sets its own reference: 0.4 is no misfit there.
  HealthMonitor young;
  for (int k = 1; k <= 10; ++k) {
    HealthInputs in = consistent(0.1 * k);
    in.n_matched = 450;
    EXPECT_EQ(young.assess(in).state, HealthState::Ok);
  }
  HealthInputs lower = consistent(1.1);
  lower.n_matched = 400;
  EXPECT_EQ(young.assess(lower).state, HealthState::Ok);
  // A failed LiDAR update degrades the frame without counting as an inconsistency.
  HealthInputs failed = consistent(0.4);
  failed.lidar_failed = true;
  failed.visual_used = true;
  h = m.assess(failed);
  EXPECT_EQ(h.state, HealthState::Degraded);
  EXPECT_FALSE(h.inconsistent);
  EXPECT_NE(h.reason.find("camera used"), std::string::npos);
  // The reason is one CSV field.
  EXPECT_EQ(h.reason.find(','), std::string::npos);
  // An overconfident filter still on the map: chi2 out of bound, but a correction (1 cm) below the
  // planes' accuracy (5 cm) is degraded and never lost, however long it lasts.
  HealthMonitor sure;
  for (int k = 1; k <= 30; ++k) {
    HealthInputs in = consistent(0.1 * k);
    in.correction_chi2 = 60.0;
    in.correction_m = 0.01;
    const FrameHealth f = sure.assess(in);
    EXPECT_EQ(f.state, HealthState::Degraded) << k;
    EXPECT_FALSE(f.inconsistent);
    EXPECT_NE(f.reason.find("(1 cm)"), std::string::npos) << f.reason;
  }
  // Isolated flags never make a lost span.
  for (int k = 5; k < 40; ++k) EXPECT_NE(m.assess(k % 6 ? consistent(0.1 * k) : inconsistent(0.1 * k)).state, HealthState::Lost);
}

TEST(Health, PersistentInconsistencyIsLostWithinTheWindowAndTheFrameStaysUnanchoredAfter) {
  HealthConfig cfg;  // window 0.5 s: lost at the third inconsistent frame of a 10 Hz run
  HealthMonitor m(cfg);
  for (int k = 1; k <= 10; ++k) ASSERT_EQ(m.assess(consistent(0.1 * k)).state, HealthState::Ok);
  std::vector<HealthState> during;
  for (int k = 11; k <= 30; ++k) during.push_back(m.assess(inconsistent(0.1 * k)).state);
  EXPECT_EQ(during[0], HealthState::Degraded);
  EXPECT_EQ(during[1], HealthState::Degraded);
  for (std::size_t i = 2; i < during.size(); ++i) EXPECT_EQ(during[i], HealthState::Lost) << i;
  // Consistent again: lost until window_s passed without an inconsistent frame ...
  EXPECT_EQ(m.assess(consistent(3.1)).state, HealthState::Lost);
  EXPECT_EQ(m.assess(consistent(3.4)).state, HealthState::Lost);
  // ... then degraded: nothing tied the frame back to the map of before the span.
  const FrameHealth after = m.assess(consistent(3.5));
  EXPECT_EQ(after.state, HealthState::Degraded);
  EXPECT_NE(after.reason.find("not re-anchored since the lost span at 1.10-3.00 s"), std::string::npos) << after.reason;
}

TEST(Health, ASpeedNoRigReachesIsLostAtOnce) {
  HealthMonitor m;
  HealthInputs fast = consistent(0.1);
  fast.speed_mps = 300.0;
  const FrameHealth h = m.assess(fast);
  EXPECT_EQ(h.state, HealthState::Lost);
  EXPECT_NE(h.reason.find("speed 300 m/s above 80"), std::string::npos) << h.reason;
  HealthInputs nan = consistent(0.2);
  nan.speed_mps = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(m.assess(nan).state, HealthState::Lost);
}

TEST(Health, ConfigKeysAreReadAndCheckedByName) {
  HealthConfig cfg;
  const ConfigFile file = ConfigFile::parse("health: {window_s: 1.0, max_speed_mps: 40, min_match_share: 0.6}");
  cfg.load(file.root().section("health"));
  EXPECT_DOUBLE_EQ(cfg.window_s, 1.0);
  EXPECT_DOUBLE_EQ(cfg.max_speed_mps, 40.0);
  EXPECT_DOUBLE_EQ(cfg.min_match_share, 0.6);
  try {
    HealthConfig bad;
    const ConfigFile wrong = ConfigFile::parse("health: {min_match_share: 1.5}");
    bad.load(wrong.root().section("health"));
    FAIL() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("min_match_share"), std::string::npos) << e.what();
  }
}
