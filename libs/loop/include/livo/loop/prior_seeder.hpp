// The map's planes for the LiDAR update when localised in a site map (loop.prior_map_planes): the site
// map's keyframes near the robot, each handed out once (one per cell of loop.keyframe_distance_m: a map of
// several laps holds each place several times), their points moved into the odometry frame by the current
// T_map_odom with the LiDAR's point covariance. livo-run --prior-map inserts them into its LiDAR map,
// livo-mapserver --prior-map into the map it serves (with T_map_odom from livo-loop's corrections).
// docs/algorithms.md section 11, "The map's planes in the LiDAR update".
#pragma once

#include "livo/loop/loop_closer.hpp"
#include "livo/loop/site_map.hpp"
#include "livo/map/point_cov.hpp"

#include <array>
#include <cstdint>
#include <set>
#include <vector>

namespace livo {

class PriorMapSeeder {
 public:
  /// `map` must outlive the seeder. Radius: loop.descriptor_range_m (the reach of a keyframe's points).
  PriorMapSeeder(SiteMap& map, const LoopConfig& cfg);
  /// The points of the map keyframes within the radius of the robot (`robot_odom`, odometry frame) not
  /// handed out before, in the odometry frame. Looks only after half a cell of travel since the last
  /// look (the scan over every map keyframe is not done each frame).
  std::vector<PointWithCov> pointsNear(const Pose& T_map_odom, const Vec3& robot_odom);
  std::size_t keyframesHanded() const { return keyframes_; }
  std::size_t pointsHanded() const { return points_; }

 private:
  SiteMap& map_;
  double radius_m_, cell_m_, range_sigma_m_, bearing_sigma_deg_;
  std::vector<bool> handed_;
  std::set<std::array<std::int64_t, 3>> cells_;
  std::size_t keyframes_ = 0, points_ = 0;
  bool have_last_ = false;
  Vec3 last_robot_ = Vec3::Zero();  ///< map-frame position of the last look
};

}  // namespace livo
