// camera.vignetting (livo/estimation/vignetting.hpp): the correction undoes the simulator's fall-off
// (two independent implementations of the model in config/sim/README.md and config/README.md), and
// the key is checked.
// livo-test-deps: livo_sim
#include "livo/common/config.hpp"
#include "livo/estimation/vignetting.hpp"
#include "livo/sensors/camera_config.hpp"
#include "livo/sim/simulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace livo;

namespace {
sim::SimScenario room(double vignetting) {
  sim::SimScenario sc;
  sc.source = "test";
  sc.seed = 3;
  sc.duration_s = 3.0;
  sc.world.kind = "room";
  sc.trajectory.static_s = 1.0;
  sc.trajectory.ramp_s = 1.0;
  sc.camera.width = 160;
  sc.camera.height = 120;
  sc.camera.fx = sc.camera.fy = 100.0;
  sc.camera.cx = 75.5;  // off centre: the farthest corner is not the mirror of every other
  sc.camera.cy = 62.5;
  sc.camera.pixel_noise = 0.0;
  sc.camera.exposure_jitter = 0.0;
  sc.camera.vignetting = vignetting;
  return sc;
}
}  // namespace

TEST(Vignetting, CorrectionUndoesTheSimulatedFallOff) {
  const Image clean = sim::Simulator(room(0.0)).renderImage(5);
  const Image dark = sim::Simulator(room(0.3)).renderImage(5);
  const VignettingCorrection corr(0.3, 160, 120, 75.5, 62.5);
  ASSERT_TRUE(corr.active());
  EXPECT_DOUBLE_EQ(corr.gainAt(75.5, 62.5), 1.0);
  EXPECT_NEAR(corr.gainAt(159, 0), 1.0 / 0.7, 1e-12);  // the farthest corner from (75.5, 62.5)
  Image fixed;
  corr.apply(dark, fixed);
  ASSERT_EQ(fixed.data.size(), clean.data.size());
  double worst = 0, before = 0;
  int n = 0;
  for (int v = 0; v < 120; ++v)
    for (int u = 0; u < 160; ++u) {
      const std::size_t i = std::size_t(v * 160 + u);
      if (clean.data[i] > 250) continue;  // saturated in the clean image: nothing to compare
      // Roundings: the clean image (0.5), the dark one scaled back (0.5 / 0.7), the correction (0.5).
      worst = std::max(worst, std::abs(double(fixed.data[i]) - clean.data[i]));
      before = std::max(before, std::abs(double(dark.data[i]) - clean.data[i]));
      ++n;
    }
  EXPECT_GT(n, 15000);
  EXPECT_LE(worst, 1.0);  // whole levels: at most 0.5 + 0.5 / 0.7 + 0.5, so 1
  EXPECT_GT(before, 10.0) << "the fall-off must be visible before the correction";
  // In place gives the same.
  Image in_place = dark;
  corr.apply(in_place, in_place);
  EXPECT_EQ(in_place.data, fixed.data);
  // Off: inactive; a wrong size is refused, not read out of bounds.
  EXPECT_FALSE(VignettingCorrection(0.0, 160, 120, 75.5, 62.5).active());
  Image small = dark;
  small.width = 80;
  EXPECT_THROW(corr.apply(small, fixed), std::invalid_argument);
}

TEST(Vignetting, RigKeyIsCheckedAndNamed) {
  const std::string rig =
      "camera:\n  width: 160\n  height: 120\n  fx: 100\n  fy: 100\n  cx: 80\n  cy: 60\n"
      "  T_imu_camera: [0, 0, 0, 0, 0, 0, 1]\n  vignetting: ";
  CameraConfig ok;
  ok.load(ConfigFile::parse(rig + "0.3\n").root());
  EXPECT_DOUBLE_EQ(ok.vignetting, 0.3);
  for (const char* bad : {"1.0", "-0.1"}) {
    CameraConfig c;
    try {
      c.load(ConfigFile::parse(rig + bad + "\n").root());
      ADD_FAILURE() << bad << " must be refused";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("camera.vignetting"), std::string::npos) << e.what();
    }
  }
}
