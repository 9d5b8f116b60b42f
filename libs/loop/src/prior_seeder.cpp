#include "livo/loop/prior_seeder.hpp"

#include <algorithm>
#include <cmath>

namespace livo {

PriorMapSeeder::PriorMapSeeder(SiteMap& map, const LoopConfig& cfg)
    : map_(map),
      radius_m_(cfg.descriptor.max_range_m),
      cell_m_(std::max(0.1, cfg.keyframes.distance_m)),
      range_sigma_m_(cfg.verify.range_sigma_m),
      bearing_sigma_deg_(cfg.verify.bearing_sigma_deg),
      handed_(map.size(), false) {}

std::vector<PointWithCov> PriorMapSeeder::pointsNear(const Pose& T_map_odom, const Vec3& robot_odom) {
  std::vector<PointWithCov> out;
  const Vec3 robot = T_map_odom * robot_odom;
  // The keyframes within reach change only as the robot moves: look again after half a cell of travel.
  if (have_last_ && (robot - last_robot_).norm() < 0.5 * cell_m_) return out;
  have_last_ = true;
  last_robot_ = robot;
  const Pose T_odom_map = T_map_odom.inverse();
  for (int i = 0; i < static_cast<int>(map_.size()); ++i) {
    if (handed_[std::size_t(i)]) continue;
    const SiteKeyframe& k = map_.keyframe(i);
    const Vec3& q = k.T_map.translation();
    if ((q - robot).norm() > radius_m_) continue;
    handed_[std::size_t(i)] = true;
    const std::array<std::int64_t, 3> cell{std::int64_t(std::floor(q.x() / cell_m_)),
                                           std::int64_t(std::floor(q.y() / cell_m_)),
                                           std::int64_t(std::floor(q.z() / cell_m_))};
    if (!cells_.insert(cell).second) continue;
    const Pose T = T_odom_map * k.T_map;
    const Mat3 R = T.linear();
    for (const Vec3& p : map_.points(i))
      out.push_back({T * p, R * pointCovarianceBody(p, range_sigma_m_, bearing_sigma_deg_) * R.transpose()});
    ++keyframes_;
  }
  points_ += out.size();
  return out;
}

}  // namespace livo
