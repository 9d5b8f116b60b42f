// A complete scenario drawn at random from the documented distribution of real rigs
// (config/sim/README.md, section "Random rigs"): world kind and size, texture and clutter; LiDAR model,
// density, blind distance, noise and range; IMU rate, noise grade, biases and vibration; camera model,
// resolution, field of view, rate and faults; extrinsics with small tilts; motion class and start (at
// rest, briefly at rest, a fast start, in motion).
//
// The draw is a pure function of the seed (SplitMix over the seed; no std:: distributions), and it is
// returned as scenario YAML so that a drawn rig can be read, saved, edited and run again with
// `livo-sim --scenario`. The rig config the estimator gets comes from `livo-sim --rig` as for any
// scenario: it knows the sensors, not the start or the world.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace livo::sim {

struct RandomScenario {
  std::string yaml;     ///< a scenario file (keys of config/sim/README.md), commented
  std::string summary;  ///< one line: what was drawn (world, LiDAR, IMU, camera, motion, start, classes)
  /// The hard classes the rig belongs to (config/sim/README.md, "Random rigs"), in this order:
  /// moving-start, fast-start, spinning-wall, spinning-room, noisy-imu, vibration-aliased or
  /// vibration, fast-camera. Also in the YAML's second line, "# classes: a, b" ("-": none).
  std::vector<std::string> classes;
};

/// Frequency at which a sinusoid of `freq_hz` shows in samples taken at `rate_hz` (in [0, rate / 2]).
double aliasedHz(double freq_hz, double rate_hz);

/// Draws scenario number `seed` of the distribution; `duration_s` is the simulated time.
RandomScenario drawRandomScenario(std::uint64_t seed, double duration_s = 30.0);

}  // namespace livo::sim
