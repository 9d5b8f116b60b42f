// Counter-based random numbers for the simulator.
//
// Every random value is a pure function of (seed, stream, index...), never of a shared generator's
// state, so that the output is bit-identical whatever the number of threads or the order in which
// pixels, points or samples are produced. Hash: SplitMix64 finaliser (Steele et al., "Fast splittable
// pseudorandom number generators", 2014) applied to a combination of the keys. Gaussians by Box-Muller
// with our own formula (std::normal_distribution differs between standard libraries).
#pragma once

#include <cmath>
#include <cstdint>

namespace livo::sim {

/// One stream per random consumer: streams never share values.
enum class RngStream : std::uint64_t {
  World = 1,
  ImuGyroNoise = 2,
  ImuAccelNoise = 3,
  ImuGyroWalk = 4,
  ImuAccelWalk = 5,
  LidarRange = 6,
  CameraPixel = 7,
  CameraExposure = 8,
  Texture = 9,
  LidarBeam = 10,
  ImuVibration = 11,
};

inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// Hash of up to four keys (order matters).
inline std::uint64_t hashKeys(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0, std::uint64_t d = 0) {
  std::uint64_t h = mix64(a);
  h = mix64(h ^ b);
  h = mix64(h ^ (c + 0x632BE59BD9B4E019ull));
  return mix64(h ^ (d + 0x8CB92BA72F3D8DD7ull));
}

/// Uniform in (0, 1) from 53 bits of a hash (never exactly 0, so log() is safe).
inline double uniformFromHash(std::uint64_t h) {
  return (static_cast<double>(h >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

/// Standard normal value for a key (Box-Muller, cosine branch).
inline double gaussianFromKeys(std::uint64_t seed, RngStream s, std::uint64_t i, std::uint64_t j = 0) {
  const std::uint64_t h = hashKeys(seed, static_cast<std::uint64_t>(s), i, j);
  const double u1 = uniformFromHash(h);
  const double u2 = uniformFromHash(mix64(h ^ 0xD1B54A32D192ED03ull));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

/// The pair of independent standard normal values of one Box-Muller draw (cosine and sine branches).
inline void gaussianPairFromKeys(std::uint64_t seed, RngStream s, std::uint64_t i, std::uint64_t j, double& a, double& b) {
  const std::uint64_t h = hashKeys(seed, static_cast<std::uint64_t>(s), i, j);
  const double u1 = uniformFromHash(h);
  const double u2 = uniformFromHash(mix64(h ^ 0xD1B54A32D192ED03ull));
  const double r = std::sqrt(-2.0 * std::log(u1)), phi = 6.283185307179586 * u2;
  a = r * std::cos(phi);
  b = r * std::sin(phi);
}

/// Sequential generator for set-up work (world layout): deterministic for a seed.
class SplitMix {
 public:
  explicit SplitMix(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() { return mix64(state_++ * 0x9E3779B97F4A7C15ull + 0x2545F4914F6CDD1Dull); }
  double uniform() { return uniformFromHash(next()); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int integer(int lo, int hi_inclusive) {
    return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi_inclusive - lo + 1));
  }
  double gaussian() {
    const double u1 = uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  std::uint64_t state_;
};

}  // namespace livo::sim
