// libs/sim: the faults of real cameras (config/sim/README.md, camera): motion blur against the mean of
// sharp images at the sub-sample times, exposure steps and vignetting against the clean image's
// pixels, stamp delay against the capture time and the written rig, and the keys' validation.
#include "sim_test_util.hpp"

#include "livo/common/config.hpp"
#include "livo/sim/simulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

using namespace livo;
using namespace livo::sim;
using namespace livo::sim::test;

namespace {

// A noise-free room with a finer camera than makeScenario's, so that blur spans several pixels.
SimScenario cameraScenario() {
  SimScenario sc = makeScenario("room");
  sc.camera.width = 160;
  sc.camera.height = 120;
  sc.camera.fx = sc.camera.fy = 100.0;
  sc.camera.cx = 79.5;
  sc.camera.cy = 59.5;
  sc.trajectory.max_rot_dps = 120.0;
  return sc;
}

// Sum of squared horizontal and vertical differences (the image's detail).
double gradientEnergy(const Image& im) {
  double e = 0;
  for (int r = 0; r + 1 < im.height; ++r)
    for (int c = 0; c + 1 < im.width; ++c) {
      const double v = im.data[std::size_t(r * im.width + c)];
      e += std::pow(im.data[std::size_t(r * im.width + c + 1)] - v, 2) + std::pow(im.data[std::size_t((r + 1) * im.width + c)] - v, 2);
    }
  return e;
}

void expectConfigError(SimScenario sc, const std::string& key) {
  try {
    sc.validate();
    ADD_FAILURE() << key << ": expected an error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
  }
}

}  // namespace

// The oracle: the sharp images at the n sub-sample times (the same scenario with the first image's
// phase shifted to each), averaged. Blurred = that average up to the two roundings (one gray level).
TEST(SimCameraFaults, MotionBlurIsTheMeanOfTheSharpImagesOverTheExposure) {
  SimScenario sc = cameraScenario();
  sc.camera.exposure_time_s = 0.03;
  const std::int64_t k = 28;  // 2.84 s: moving (1 s static, 1 s ramp)
  const Simulator blurred(sc);
  ImageTruth truth;
  const Image b = blurred.renderImage(k, &truth);
  const int n = truth.blur_samples;
  ASSERT_EQ(n, blurred.blurSamples(k));
  ASSERT_GE(n, 4) << "the test needs motion over the exposure";
  EXPECT_EQ(b.utime, blurred.cameraUtime(k));  // no stamp delay
  std::vector<double> mean(b.data.size(), 0.0);
  for (int s = 0; s < n; ++s) {
    SimScenario sharp = sc;
    sharp.camera.exposure_time_s = 0.0;
    sharp.camera.phase_s += sc.camera.exposure_time_s * ((s + 0.5) / n - 0.5);
    const Image im = Simulator(sharp).renderImage(k);
    for (std::size_t i = 0; i < mean.size(); ++i) mean[i] += double(im.data[i]) / n;
  }
  double worst = 0;
  for (std::size_t i = 0; i < mean.size(); ++i) worst = std::max(worst, std::abs(double(b.data[i]) - mean[i]));
  EXPECT_LE(worst, 1.05);  // + the sub-sample times' rounding to microseconds
  // And it is blur: less detail than the sharp image at the capture time.
  SimScenario sharp = sc;
  sharp.camera.exposure_time_s = 0.0;
  const Image s = Simulator(sharp).renderImage(k);
  EXPECT_LT(gradientEnergy(b), 0.9 * gradientEnergy(s));
  // At rest (frame 3, 0.34 s) nothing moves: one sample, the sharp image.
  EXPECT_EQ(blurred.blurSamples(3), 1);
  EXPECT_EQ(blurred.renderImage(3).data, Simulator(sharp).renderImage(3).data);
}

TEST(SimCameraFaults, ExposureStepsAndVignettingScaleTheCleanImage) {
  SimScenario sc = cameraScenario();
  const Simulator clean(sc);
  sc.camera.exposure_steps = {1.0, 2.0, 2.0, 0.25};  // x2 from 1 s, then /4 (x0.5 in all) from 2 s
  const Simulator stepped(sc);
  for (const auto& [k, factor] : {std::pair<std::int64_t, double>{5, 1.0}, {15, 2.0}, {25, 0.5}}) {
    ImageTruth t;
    const Image a = clean.renderImage(k), b = stepped.renderImage(k, &t);
    EXPECT_DOUBLE_EQ(t.gain, factor) << k;
    int n = 0;
    for (std::size_t i = 0; i < a.data.size(); ++i) {
      if (a.data[i] < 20 || a.data[i] * factor > 235) continue;  // away from clamping and rounding's share
      EXPECT_NEAR(b.data[i], a.data[i] * factor, 0.5 + 0.5 * factor) << "frame " << k << " pixel " << i;
      ++n;
    }
    EXPECT_GT(n, 1000) << k;
  }
  sc = cameraScenario();
  sc.camera.vignetting = 0.3;
  const Simulator vignetted(sc);
  const Image a = clean.renderImage(10), v = vignetted.renderImage(10);
  const double r2_corner = 79.5 * 79.5 + 59.5 * 59.5;
  int n = 0;
  for (int r = 0; r < a.height; ++r)
    for (int c = 0; c < a.width; ++c) {
      const std::size_t i = std::size_t(r * a.width + c);
      if (a.data[i] < 20 || a.data[i] > 250) continue;
      const double f = 1.0 - 0.3 * ((c - 79.5) * (c - 79.5) + (r - 59.5) * (r - 59.5)) / r2_corner;
      EXPECT_NEAR(v.data[i], a.data[i] * f, 1.0) << r << ", " << c;
      ++n;
    }
  EXPECT_GT(n, 1000);
}

TEST(SimCameraFaults, StampDelayStampsLateAndTheRigCorrectsIt) {
  SimScenario sc = cameraScenario();
  sc.camera.stamp_delay_s = 0.015;
  Simulator sim(sc);
  ImageTruth t;
  const Image im = sim.renderImage(12, &t);
  EXPECT_EQ(t.capture_utime, sim.cameraUtime(12));
  EXPECT_EQ(im.utime, t.capture_utime + 15000);
  EXPECT_EQ(sim.cameraStamp(12), im.utime);
  // Pixels are those of the capture time: the same as without the delay.
  SimScenario on_time = sc;
  on_time.camera.stamp_delay_s = 0.0;
  EXPECT_EQ(Simulator(on_time).renderImage(12).data, im.data);
  // The event stream is ordered by stamp, and the images carry the late stamps.
  SimEvent ev;
  Utime last = 0;
  int images = 0;
  while (sim.next(ev)) {
    EXPECT_GE(ev.utime, last);
    last = ev.utime;
    if (ev.kind == SimEvent::Kind::Image) {
      EXPECT_EQ(ev.image.utime, ev.image_truth.capture_utime + 15000);
      EXPECT_EQ(ev.utime, ev.image.utime);
      ++images;
    }
  }
  EXPECT_EQ(images, 40);
  std::ostringstream rig;
  sim.writeRigConfig(rig);
  const std::string text = rig.str();
  const std::size_t camera = text.find("\ncamera:\n");
  ASSERT_NE(camera, std::string::npos) << text;
  EXPECT_NE(text.find("  time_offset_s: -0.015\n", camera), std::string::npos) << text;
}

TEST(SimCameraFaults, BadKeysAreErrorsNamingThem) {
  SimScenario sc = cameraScenario();
  sc.camera.exposure_time_s = -0.001;
  expectConfigError(sc, "camera.exposure_time_s");
  sc = cameraScenario();
  sc.camera.exposure_time_s = 0.1;  // the whole frame interval at 10 Hz
  expectConfigError(sc, "camera.exposure_time_s");
  sc = cameraScenario();
  sc.camera.exposure_steps = {1.0, 2.0, 3.0};
  expectConfigError(sc, "camera.exposure_steps");
  sc.camera.exposure_steps = {1.0, 0.0};
  expectConfigError(sc, "camera.exposure_steps");
  sc.camera.exposure_steps = {2.0, 2.0, 1.0, 0.5};
  expectConfigError(sc, "camera.exposure_steps");
  sc = cameraScenario();
  sc.camera.vignetting = 1.0;
  expectConfigError(sc, "camera.vignetting");
  sc = cameraScenario();
  sc.camera.stamp_delay_s = 0.06;  // beyond half the frame interval at 10 Hz
  expectConfigError(sc, "camera.stamp_delay_s");
  sc.camera.stamp_delay_s = -0.01;
  expectConfigError(sc, "camera.stamp_delay_s");
  // Through the scenario file's parser: the keys are known.
  const SimScenario parsed = parseScenario(
      "camera:\n  exposure_time_s: 0.008\n  exposure_steps: [10, 2, 20, 0.5]\n  vignetting: 0.3\n  stamp_delay_s: 0.015\n");
  EXPECT_DOUBLE_EQ(parsed.camera.exposure_time_s, 0.008);
  EXPECT_EQ(parsed.camera.exposure_steps, (std::vector<double>{10, 2, 20, 0.5}));
  EXPECT_DOUBLE_EQ(parsed.camera.vignetting, 0.3);
  EXPECT_DOUBLE_EQ(parsed.camera.stamp_delay_s, 0.015);
}
