#include "livo/loop/packed_points.hpp"

#include <algorithm>
#include <cmath>

namespace livo {

PackedPoints::PackedPoints(const std::vector<Vec3>& points, double range_m) : step_(std::max(0.01, range_m / 32000.0)) {
  const double r2 = range_m * range_m;
  q_.reserve(points.size());
  for (const Vec3& p : points) {
    if (!p.allFinite() || p.head<2>().squaredNorm() > r2 || std::abs(p.z()) > range_m) continue;
    q_.push_back({static_cast<std::int16_t>(std::lround(p.x() / step_)), static_cast<std::int16_t>(std::lround(p.y() / step_)),
                  static_cast<std::int16_t>(std::lround(p.z() / step_))});
  }
  q_.shrink_to_fit();
}

std::vector<Vec3> PackedPoints::unpack() const {
  std::vector<Vec3> out;
  out.reserve(q_.size());
  for (const auto& q : q_) out.emplace_back(q[0] * step_, q[1] * step_, q[2] * step_);
  return out;
}

}  // namespace livo
