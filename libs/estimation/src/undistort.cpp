#include "livo/estimation/undistort.hpp"

namespace livo {

std::vector<LidarPoint> undistortToEnd(const LidarScan& sweep, const std::vector<ImuTracePoint>& trace,
                                       const Pose& T_imu_lidar) {
  std::vector<LidarPoint> out;
  out.reserve(sweep.points.size());
  if (trace.empty()) return out;
  const Pose T_end_inv = ImuPropagator::poseAt(trace, trace.back().utime).inverse();
  for (const auto& p : sweep.points) {
    const Utime t = sweep.utime + fromSeconds(p.time_offset_s);
    const Pose T_world_imu_t = ImuPropagator::poseAt(trace, t);
    const Vec3 p_end = T_end_inv * (T_world_imu_t * (T_imu_lidar * p.p_lidar.cast<double>()));
    LidarPoint q = p;
    q.p_lidar = p_end.cast<float>();
    out.push_back(q);
  }
  return out;
}

}  // namespace livo
