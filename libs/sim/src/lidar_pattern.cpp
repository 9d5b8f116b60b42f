#include "livo/sim/lidar_pattern.hpp"

#include <cmath>

namespace livo::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Direction of azimuth (about +z, from +x towards +y) and elevation (towards +z).
inline Vec3 fromAzEl(double az, double el) {
  return Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
}

// Avia rosette: two prisms at f1 and f2 Hz (opposite signs, incommensurate). The unit-disc point
// 0.5 (e^{i w1 t} + e^{i (w2 t + phase)}) has radius |cos((w1 - w2) t / 2)| (petals through the
// centre, 151.3 per second per laser) and angle (w1 + w2) t / 2 (the petals precess, 8 Hz).
constexpr double kAviaF1 = 83.7, kAviaF2 = -67.6;
constexpr double kAviaHalfH = 35.2 * kDeg, kAviaHalfV = 38.6 * kDeg;

// Mid-360: head rotation and elevation sweep rates (incommensurate with each other and 10 Hz).
constexpr double kMidRevHz = 10.37, kMidElHz = 213.7;
constexpr double kMidElMin = -7.0 * kDeg, kMidElMax = 52.0 * kDeg;

constexpr double kSpinElMin = -22.5 * kDeg, kSpinElMax = 22.5 * kDeg;

}  // namespace

LidarPattern::LidarPattern(const LidarSimConfig& cfg) {
  if (cfg.model == "mid360") {
    model_ = Model::Mid360;
    lasers_ = 4;
    pps_ = 200000.0;
  } else if (cfg.model == "spinning32") {
    model_ = Model::Spinning32;
    lasers_ = 32;
    pps_ = 327680.0;
  }
  if (cfg.points_per_second > 0.0) pps_ = cfg.points_per_second;
  firings_ = std::max(1, static_cast<int>(std::lround(pps_ / (lasers_ * cfg.rate_hz))));
  firing_dt_ = 1.0 / (cfg.rate_hz * firings_);
}

Vec3 LidarPattern::direction(double t, int laser, int firing) const {
  switch (model_) {
    case Model::Avia: {
      const double w1 = 2.0 * kPi * kAviaF1, w2 = 2.0 * kPi * kAviaF2;
      const double rot = laser * (2.0 * kPi / 6.0) + 0.37 * laser;  // spread the six lasers' petals
      const double x = 0.5 * (std::cos(w1 * t) + std::cos(w2 * t + rot));
      const double y = 0.5 * (std::sin(w1 * t) + std::sin(w2 * t + rot));
      return fromAzEl(kAviaHalfH * x, kAviaHalfV * y);
    }
    case Model::Mid360: {
      const double az = 2.0 * kPi * kMidRevHz * t;
      double phase = kMidElHz * t + 0.25 * laser;
      phase -= std::floor(phase);
      const double tri = phase < 0.5 ? 2.0 * phase : 2.0 - 2.0 * phase;  // triangle wave 0..1
      return fromAzEl(az, kMidElMin + (kMidElMax - kMidElMin) * tri);
    }
    case Model::Spinning32: {
      const double az = 2.0 * kPi * firing / firings_;
      return fromAzEl(az, kSpinElMin + (kSpinElMax - kSpinElMin) * laser / 31.0);
    }
  }
  return Vec3::UnitX();
}

void LidarPattern::rays(double scan_start_s, std::vector<LidarRay>& out) const {
  out.resize(static_cast<std::size_t>(firings_) * lasers_);
  std::size_t k = 0;
  for (int f = 0; f < firings_; ++f) {
    const auto offset = static_cast<float>(f * firing_dt_);
    // Directions at the time the receiver reconstructs: scan start + the float offset.
    const double t = scan_start_s + static_cast<double>(offset);
    for (int l = 0; l < lasers_; ++l, ++k) {
      out[k].time_offset_s = offset;
      out[k].ring = static_cast<std::int16_t>(l);
      out[k].dir = direction(t, l, f);
    }
  }
}

}  // namespace livo::sim
