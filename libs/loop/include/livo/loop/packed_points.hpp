// A keyframe's stored points, 6 bytes each: int16 coordinates in steps of step_m = max(1 cm, range / 32000)
// in the keyframe frame. The rounding error (uniform, sigma step / sqrt(12): 2.9 mm at 1 cm) stays below
// a LiDAR's range noise; the loop closer keeps one such set per keyframe for verification.
#pragma once

#include "livo/common/so3.hpp"

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace livo {

class PackedPoints {
 public:
  PackedPoints() = default;
  /// Keeps the points within `range_m` horizontally and vertically of the origin (others, and non-finite
  /// ones, are left out).
  PackedPoints(const std::vector<Vec3>& points, double range_m);
  /// Already packed coordinates (read back from a spill file).
  PackedPoints(std::vector<std::array<std::int16_t, 3>> packed, double step_m) : step_(step_m), q_(std::move(packed)) {}
  std::vector<Vec3> unpack() const;
  const std::vector<std::array<std::int16_t, 3>>& packed() const { return q_; }
  std::size_t size() const { return q_.size(); }
  std::size_t bytes() const { return q_.capacity() * sizeof(q_[0]); }
  double step() const { return step_; }

 private:
  double step_ = 0.01;
  std::vector<std::array<std::int16_t, 3>> q_;
};

}  // namespace livo
