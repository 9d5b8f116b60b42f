// Shared helpers of the libs/loop tests (tests/test_loop_*.cpp): the simulator's revisit scenario and its
// scans as the odometry would register them, without the odometry's error.
#pragma once

#include "livo/loop/loop_verifier.hpp"
#include "livo/sim/simulator.hpp"

#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace livo::test {

inline double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

/// config/sim/revisit.yaml: a 340 m city block driven three times at 8 m/s.
inline sim::SimScenario revisitScenario() {
  return sim::loadScenarioFile(std::string(LIVO_SOURCE_DIR) + "/config/sim/revisit.yaml");
}

/// Scan j of the simulator in the world frame, each point at the true pose of its own time.
inline std::vector<Vec3> worldScan(const sim::Simulator& s, std::int64_t j) {
  const LidarScan scan = s.lidarScan(j);
  std::map<float, Pose> at;
  std::vector<Vec3> out;
  out.reserve(scan.points.size());
  for (const LidarPoint& p : scan.points) {
    auto it = at.find(p.time_offset_s);
    if (it == at.end())
      it = at.emplace(p.time_offset_s, s.T_world_lidar(scan.utime + fromSeconds(p.time_offset_s))).first;
    out.push_back(it->second * p.p_lidar.cast<double>());
  }
  return out;
}

/// The drifting odometry of the loop tests: the truth's step from `prev_truth` to `truth`, 0.5 % too long
/// and turned 0.004 deg too far about z (about 5 m and 5 deg over the revisit scenario's 1040 m).
inline Pose driftedStep(const Pose& prev_truth, const Pose& truth) {
  Pose step = prev_truth.inverse() * truth;
  step.translation() *= 1.005;
  step.linear() = Eigen::AngleAxisd(0.004 * M_PI / 180.0, Vec3::UnitZ()).toRotationMatrix() * step.linear();
  return step;
}

/// World points in the keyframe frame of body pose T (keyframeFrame: position and heading).
inline std::vector<Vec3> inKeyframe(const std::vector<Vec3>& world, const Pose& T_world_body) {
  const Pose K_inv = keyframeFrame(T_world_body).inverse();
  std::vector<Vec3> out;
  out.reserve(world.size());
  for (const Vec3& p : world) out.push_back(K_inv * p);
  return out;
}

}  // namespace livo::test
