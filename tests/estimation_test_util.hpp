// Helpers shared by the libs/estimation tests.
#pragma once

#include "livo/estimation/state.hpp"

#include <random>

namespace livo_test {

/// A random but plausible navigation state (seeded by the caller).
inline livo::NavState randomState(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  livo::NavState x;
  x.utime = 1700000000000000;
  x.R_world_imu = livo::expSO3(livo::Vec3(n(rng), n(rng), n(rng)));
  x.p_world_imu = livo::Vec3(n(rng), n(rng), n(rng)) * 3;
  x.inv_exposure = 1.2;
  x.v_world = livo::Vec3(n(rng), n(rng), n(rng));
  x.bg = livo::Vec3(n(rng), n(rng), n(rng)) * 0.01;
  x.ba = livo::Vec3(n(rng), n(rng), n(rng)) * 0.1;
  x.g_world = livo::Vec3(0.1, -0.05, -9.8);
  return x;
}

}  // namespace livo_test
