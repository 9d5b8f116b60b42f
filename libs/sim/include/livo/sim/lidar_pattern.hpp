// Scan patterns of the simulated LiDARs: ray directions (LiDAR frame) and firing times.
//
// - avia: 6 lasers, each tracing a non-repetitive rosette (two counter-rotating prisms: the direction
//   is the sum of two circles turning at incommensurate rates), scaled to 70.4 x 77.2 deg; 240k pts/s.
// - mid360: 4 lasers on a head turning ~10.4 rev/s while each sweeps elevation -7..52 deg with a
//   triangle wave at an incommensurate rate; 200k pts/s.
// - spinning32: 32 rings from -22.5 to +22.5 deg, 1024 columns per turn at 10 Hz (327,680 pts/s),
//   all rings of a column fire together.
// Avia and Mid-360 look along +x; spinning32 spins about +z (counter-clockwise from +x).
#pragma once

#include "livo/common/so3.hpp"
#include "livo/sim/scenario.hpp"

#include <cstdint>
#include <vector>

namespace livo::sim {

struct LidarRay {
  float time_offset_s = 0.f;  ///< after the scan start, as sent in the message
  std::int16_t ring = 0;
  Vec3 dir = Vec3::UnitX();   ///< unit vector, LiDAR frame
};

class LidarPattern {
 public:
  explicit LidarPattern(const LidarSimConfig& cfg);
  /// Rays of a scan starting `scan_start_s` seconds after the sensor's first scan, in firing order
  /// (rays of one firing are consecutive and share a time offset).
  void rays(double scan_start_s, std::vector<LidarRay>& out) const;

  int lasers() const { return lasers_; }
  double pointsPerSecond() const { return pps_; }
  int firingsPerScan() const { return firings_; }

 private:
  Vec3 direction(double t, int laser, int firing) const;

  enum class Model { Avia, Mid360, Spinning32 } model_ = Model::Avia;
  int lasers_ = 6;
  double pps_ = 240000.0;
  int firings_ = 4000;
  double firing_dt_ = 25e-6;
};

}  // namespace livo::sim
