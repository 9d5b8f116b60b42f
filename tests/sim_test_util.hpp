// Shared helpers of the libs/sim tests (tests/test_sim_*.cpp): pi and a small, fast scenario.
#pragma once

#include "livo/sim/simulator.hpp"

#include <string>

namespace livo::sim::test {

inline constexpr double kPi = 3.14159265358979323846;

// A small, fast scenario; noise-free unless `noisy`.
inline SimScenario makeScenario(const std::string& world, const std::string& lidar = "avia", bool noisy = false) {
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

}  // namespace livo::sim::test
