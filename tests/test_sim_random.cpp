// libs/sim random rigs (drawRandomScenario, `livo-sim --random SEED`): the draw is a pure function of
// the seed, every draw is a valid scenario, the draws span the distribution of config/sim/README.md
// ("Random rigs"), and each rig's classes and summary line say what the scenario holds (the classes
// recomputed here from the parsed scenario, not from the generator's variables).
#include "livo/sim/random_scenario.hpp"
#include "livo/sim/simulator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

using namespace livo;
using namespace livo::sim;

namespace {

constexpr int kDraws = 400;

/// The classes of a scenario by their definitions (config/sim/README.md, "Random rigs").
std::vector<std::string> classesOf(const SimScenario& sc) {
  std::vector<std::string> c;
  const auto& tr = sc.trajectory;
  if (tr.static_s == 0.0 && tr.ramp_s == 0.0) c.push_back("moving-start");
  if (tr.static_s > 0.0 && tr.static_s < 0.5) c.push_back("fast-start");
  if (sc.lidar.model == "spinning32" && (sc.world.kind == "wall" || sc.world.kind == "room"))
    c.push_back("spinning-" + sc.world.kind);
  if (sc.imu.gyro_noise > 10.0 * 1.7e-4) c.push_back("noisy-imu");
  if (sc.imu.vibration.active()) c.push_back(sc.imu.vibration.freq_hz > 0.5 * sc.imu.rate_hz ? "vibration-aliased" : "vibration");
  if (sc.camera.rate_hz >= 2.0 * sc.lidar.rate_hz - 1e-9) c.push_back("fast-camera");
  return c;
}

}  // namespace

TEST(SimRandom, AliasedFrequency) {
  EXPECT_DOUBLE_EQ(aliasedHz(91.0, 100.0), 9.0);
  EXPECT_DOUBLE_EQ(aliasedHz(41.0, 100.0), 41.0);
  EXPECT_DOUBLE_EQ(aliasedHz(150.0, 100.0), 50.0);
  EXPECT_DOUBLE_EQ(aliasedHz(230.0, 200.0), 30.0);
  EXPECT_DOUBLE_EQ(aliasedHz(250.0, 250.0), 0.0);
}

// The draw is a pure function of the seed, and every draw is a valid scenario whose worlds, starts,
// sensors and classes span the documented distribution.
TEST(SimRandom, DeterministicValidAndSpanningTheDistribution) {
  EXPECT_EQ(drawRandomScenario(7).yaml, drawRandomScenario(7).yaml);
  EXPECT_EQ(drawRandomScenario(7).summary, drawRandomScenario(7).summary);
  EXPECT_NE(drawRandomScenario(7).yaml, drawRandomScenario(8).yaml);
  std::map<std::string, int> worlds, class_count;
  std::map<std::string, std::map<std::string, int>> lidar_in;  // world -> model -> draws
  int at_rest = 0, brief = 0, vibrating = 0, walk_over_5 = 0, low_grade_high_walk = 0;
  double max_accel_vib = 0.0, max_gyro_vib = 0.0, min_freq = 1e9, max_freq = 0.0, max_walk = 0.0;
  std::set<std::string> fast_camera_lidars;
  std::set<double> camera_factors;
  for (int s = 1; s <= kDraws; ++s) {
    SCOPED_TRACE("seed " + std::to_string(s));
    const RandomScenario drawn = drawRandomScenario(static_cast<std::uint64_t>(s), 12.0);
    SimScenario sc;
    ASSERT_NO_THROW(sc = parseScenario(drawn.yaml));
    ++worlds[sc.world.kind];
    ++lidar_in[sc.world.kind][sc.lidar.model];
    const auto& tr = sc.trajectory;
    // Motion, written out: car or drone on a street, handheld at a wall, handheld or drone elsewhere.
    const std::set<std::string> motions = sc.world.kind == "street" ? std::set<std::string>{"car", "drone"}
                                          : sc.world.kind == "wall" ? std::set<std::string>{"handheld"}
                                                                    : std::set<std::string>{"handheld", "drone"};
    EXPECT_EQ(motions.count(tr.motion), 1u) << tr.motion;

    // Starts: at rest 1.5-3 s, briefly at rest 0.5-1.5 s (both then a ramp of 0.5-2.5 s), a fast start
    // (under 0.5 s at rest, then the vehicle's acceleration: ramp = 1.875 x cruise / acceleration), or
    // at cruise from the first sample.
    if (tr.static_s >= 1.5) {
      ++at_rest;
      EXPECT_LE(tr.static_s, 3.0);
      EXPECT_TRUE(tr.ramp_s >= 0.5 && tr.ramp_s <= 2.5);
      EXPECT_NE(drawn.summary.find(", rest "), std::string::npos) << drawn.summary;
    } else if (tr.static_s >= 0.5) {
      ++brief;
      EXPECT_TRUE(tr.ramp_s >= 0.5 && tr.ramp_s <= 2.5);
      EXPECT_NE(drawn.summary.find("short rest"), std::string::npos) << drawn.summary;
    } else if (tr.static_s > 0.0) {
      EXPECT_GE(tr.static_s, 0.05);
      EXPECT_NEAR(tr.ramp_s, 1.875 * tr.speed_mps / tr.max_accel_mps2, 1e-5 * tr.ramp_s);
      EXPECT_NE(drawn.summary.find("m/s^2 acceleration"), std::string::npos) << drawn.summary;
    } else {
      EXPECT_EQ(tr.ramp_s, 0.0);
      EXPECT_NE(drawn.summary.find("from the first sample"), std::string::npos) << drawn.summary;
    }

    // IMU: noise 0.5-30x, bias walks 0.5-10x the shipped ones apart from the noise grade.
    const double grade = sc.imu.gyro_noise / 1.7e-4;
    EXPECT_NEAR(sc.imu.accel_noise / 2.0e-3, grade, 1e-4 * grade);
    EXPECT_TRUE(grade >= 0.5 - 1e-6 && grade <= 30.0 + 1e-6) << grade;
    for (const double walk : {sc.imu.gyro_bias_walk / 1.9e-5, sc.imu.accel_bias_walk / 3.0e-3}) {
      EXPECT_TRUE(walk >= 0.5 - 1e-6 && walk <= 10.0 + 1e-6) << walk;
      max_walk = std::max(max_walk, walk);
      walk_over_5 += walk > 5.0;
      low_grade_high_walk += grade < 2.0 && walk > 5.0;
    }
    EXPECT_TRUE(sc.imu.rate_hz == 100.0 || sc.imu.rate_hz == 200.0 || sc.imu.rate_hz == 250.0 || sc.imu.rate_hz == 400.0);
    // Vibration: 0.05-3 m/s^2 and 0.005-0.06 rad/s RMS at 20-250 Hz, named against the IMU's rate.
    const auto& v = sc.imu.vibration;
    if (v.active()) {
      ++vibrating;
      EXPECT_TRUE(v.accel_mps2 >= 0.05 - 1e-9 && v.accel_mps2 <= 3.0 + 1e-9) << v.accel_mps2;
      EXPECT_TRUE(v.gyro_rad_s >= 0.005 - 1e-9 && v.gyro_rad_s <= 0.06 + 1e-9) << v.gyro_rad_s;
      EXPECT_TRUE(v.freq_hz >= 20.0 && v.freq_hz <= 250.0) << v.freq_hz;
      max_accel_vib = std::max(max_accel_vib, v.accel_mps2);
      max_gyro_vib = std::max(max_gyro_vib, v.gyro_rad_s);
      min_freq = std::min(min_freq, v.freq_hz);
      max_freq = std::max(max_freq, v.freq_hz);
      char hz[32];
      std::snprintf(hz, sizeof hz, "%g Hz IMU", sc.imu.rate_hz);
      EXPECT_NE(drawn.summary.find(hz), std::string::npos) << drawn.summary;
      EXPECT_EQ(drawn.summary.find("aliased to") != std::string::npos, v.freq_hz > 0.5 * sc.imu.rate_hz) << drawn.summary;
    }

    // Camera: 0.5 / 1 / 1.5 / 2 / 3 times the LiDAR's rate whatever the LiDAR, at most 8 Mpixel/s.
    const double factor = sc.camera.rate_hz / sc.lidar.rate_hz;
    camera_factors.insert(factor);
    EXPECT_TRUE(factor == 0.5 || factor == 1.0 || factor == 1.5 || factor == 2.0 || factor == 3.0) << factor;
    EXPECT_LE(double(sc.camera.width) * sc.camera.height * sc.camera.rate_hz, 8e6);
    EXPECT_TRUE(sc.camera.width >= 320 && sc.camera.width <= 1280);
    if (factor >= 2.0) fast_camera_lidars.insert(sc.lidar.model);

    // The classes: as defined, in the YAML's second line and at the end of the summary.
    const std::vector<std::string> classes = classesOf(sc);
    EXPECT_EQ(drawn.classes, classes);
    std::string list;
    for (const auto& c : classes) list += (list.empty() ? "" : ", ") + c;
    const std::string second_line = drawn.yaml.substr(drawn.yaml.find('\n') + 1, drawn.yaml.find('\n', drawn.yaml.find('\n') + 1) - drawn.yaml.find('\n') - 1);
    EXPECT_EQ(second_line, "# classes: " + (classes.empty() ? std::string("-") : list));
    if (!classes.empty()) {
      EXPECT_NE(drawn.summary.find("[" + list + "]"), std::string::npos) << drawn.summary;
    }
    for (const auto& c : classes) ++class_count[c];
  }
  // Worlds 35 / 25 / 25 / 15 %; starts 35 / 15 / 20 / 30 %.
  EXPECT_GE(worlds["room"], 100);
  EXPECT_GE(worlds["corridor"], 70);
  EXPECT_GE(worlds["street"], 70);
  EXPECT_GE(worlds["wall"], 35);
  EXPECT_GE(at_rest, 105);
  EXPECT_GE(brief, 35);
  // The spinning LiDAR as often in every world (a third): walls and rooms included.
  for (const auto& [world, models] : lidar_in) {
    SCOPED_TRACE(world);
    const double n = worlds[world];
    const double spinning = models.count("spinning32") ? models.at("spinning32") : 0;
    EXPECT_GT(spinning / n, 0.15);
    EXPECT_LT(spinning / n, 0.55);
  }
  // Every class is drawn: moving 30 %, fast start 20 %, spinning on a wall 5 %, in a room 12 %, IMU
  // noise over 10x 27 %, vibration 30 % (aliased in about 57 % of those), camera at 2-3x 35 %.
  EXPECT_GE(class_count["moving-start"], 90);
  EXPECT_GE(class_count["fast-start"], 55);
  EXPECT_GE(class_count["spinning-wall"], 8);
  EXPECT_GE(class_count["spinning-room"], 30);
  EXPECT_GE(class_count["noisy-imu"], 75);
  EXPECT_GE(class_count["vibration-aliased"], 45);
  EXPECT_GE(class_count["vibration"], 25);
  EXPECT_GE(class_count["fast-camera"], 100);
  EXPECT_GE(vibrating, 95);
  // The ranges are used to their ends: vibration up to 3 m/s^2 and 0.06 rad/s at 20-250 Hz, bias walks
  // up to 10x also with a quiet IMU, every camera factor, fast cameras with every LiDAR.
  EXPECT_GT(max_accel_vib, 2.0);
  EXPECT_GT(max_gyro_vib, 0.045);
  EXPECT_LT(min_freq, 35.0);
  EXPECT_GT(max_freq, 235.0);
  EXPECT_GT(max_walk, 8.0);
  EXPECT_GE(walk_over_5, 60);
  EXPECT_GE(low_grade_high_walk, 5);
  EXPECT_EQ(camera_factors.size(), 5u);
  EXPECT_EQ(fast_camera_lidars.size(), 3u);
}
