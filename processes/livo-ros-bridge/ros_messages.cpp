// The estimator's outputs as ROS messages (conventions in ros_messages.hpp).
#include "ros_messages.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cstdio>
#include <type_traits>
#include <cstring>

namespace livo_bridge {

namespace {

diagnostic_msgs::KeyValue kv(const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue k;
  k.key = key;
  k.value = value;
  return k;
}

template <class T>
diagnostic_msgs::KeyValue kv(const std::string& key, T value) {
  if constexpr (std::is_floating_point_v<T>) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.4g", static_cast<double>(value));
    return kv(key, std::string(buf));
  } else {
    return kv(key, std::to_string(value));
  }
}

}  // namespace

ros::Time rosTime(livo::Utime utime) {
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(utime < 0 ? 0 : utime) * 1000);
  return t;
}

livo::Mat6 rosPoseCovariance(const livo::Mat3& R_world_imu, const livo::Mat6& cov_rot_pos) {
  livo::Mat6 J = livo::Mat6::Zero();
  J.block<3, 3>(0, 3) = livo::Mat3::Identity();  // position rows <- dp
  J.block<3, 3>(3, 0) = R_world_imu;             // world rotation rows <- R dtheta
  return J * cov_rot_pos * J.transpose();
}

nav_msgs::Odometry toRosOdometry(const livo::OdometryOutput& o, const std::string& world_frame,
                                 const std::string& body_frame) {
  nav_msgs::Odometry m;
  m.header.stamp = rosTime(o.utime);
  m.header.frame_id = world_frame;
  m.child_frame_id = body_frame;
  const livo::NavState& s = o.state;
  const Eigen::Quaterniond q(s.R_world_imu);
  m.pose.pose.position.x = s.p_world_imu.x();
  m.pose.pose.position.y = s.p_world_imu.y();
  m.pose.pose.position.z = s.p_world_imu.z();
  m.pose.pose.orientation.x = q.x();
  m.pose.pose.orientation.y = q.y();
  m.pose.pose.orientation.z = q.z();
  m.pose.pose.orientation.w = q.w();
  const livo::Mat6 c = rosPoseCovariance(s.R_world_imu, o.pose_cov);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) m.pose.covariance[6 * i + j] = c(i, j);
  const livo::Vec3 v_body = s.R_world_imu.transpose() * s.v_world;
  m.twist.twist.linear.x = v_body.x();
  m.twist.twist.linear.y = v_body.y();
  m.twist.twist.linear.z = v_body.z();
  m.twist.covariance[0] = -1;
  return m;
}

geometry_msgs::TransformStamped toRosTransform(const livo::OdometryOutput& o, const std::string& world_frame,
                                               const std::string& body_frame) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = rosTime(o.utime);
  t.header.frame_id = world_frame;
  t.child_frame_id = body_frame;
  const Eigen::Quaterniond q(o.state.R_world_imu);
  t.transform.translation.x = o.state.p_world_imu.x();
  t.transform.translation.y = o.state.p_world_imu.y();
  t.transform.translation.z = o.state.p_world_imu.z();
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  return t;
}

void fillCloud(sensor_msgs::PointCloud2& out, std::size_t n, const float* x, const float* y, const float* z,
               const float* intensity, const std::int32_t* rgb) {
  out.height = 1;
  out.width = static_cast<std::uint32_t>(n);
  out.fields.clear();
  std::uint32_t offset = 0;
  for (const char* name : {"x", "y", "z", "intensity", "rgb"}) {
    if (!rgb && std::strcmp(name, "rgb") == 0) break;
    sensor_msgs::PointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    out.fields.push_back(f);
    offset += 4;
  }
  out.is_bigendian = false;
  out.point_step = offset;
  out.row_step = offset * out.width;
  out.is_dense = true;
  out.data.resize(static_cast<std::size_t>(out.row_step));
  std::uint8_t* p = out.data.data();
  for (std::size_t i = 0; i < n; ++i, p += offset) {
    std::memcpy(p, x + i, 4);
    std::memcpy(p + 4, y + i, 4);
    std::memcpy(p + 8, z + i, 4);
    std::memcpy(p + 12, intensity + i, 4);
    if (rgb) {
      const std::uint32_t c = rgb[i] < 0 ? 0xFFFFFFu : static_cast<std::uint32_t>(rgb[i]);
      std::memcpy(p + 16, &c, 4);
    }
  }
}

sensor_msgs::PointCloud2 toRosCloud(const livo::registered_scan_t& m, const std::string& world_frame) {
  sensor_msgs::PointCloud2 c;
  c.header.stamp = rosTime(m.utime);
  c.header.frame_id = world_frame;
  const bool coloured = m.num_colors > 0 && m.num_colors == m.num_points;
  fillCloud(c, static_cast<std::size_t>(m.num_points), m.x.data(), m.y.data(), m.z.data(), m.intensity.data(),
            coloured ? m.rgb.data() : nullptr);
  return c;
}

diagnostic_msgs::DiagnosticStatus estimatorStatus(const livo::OdometryOutput* odo, const livo::EstimatorStats* st) {
  namespace os = livo::odometry_status;
  diagnostic_msgs::DiagnosticStatus d;
  d.name = "livo: estimator";
  d.hardware_id = "livo";
  if (!odo) {
    d.level = diagnostic_msgs::DiagnosticStatus::STALE;
    d.message = "no odometry (is livo-estimator running?)";
    return d;
  }
  d.level = diagnostic_msgs::DiagnosticStatus::OK;
  std::string msg;
  auto flag = [&](std::int32_t bit, const char* text, int level) {
    if (!(odo->status & bit)) return;
    msg += (msg.empty() ? "" : ", ") + std::string(text);
    d.level = static_cast<std::int8_t>(std::max<int>(d.level, level));
  };
  flag(os::kInitializing, "initializing", diagnostic_msgs::DiagnosticStatus::WARN);
  flag(os::kDegenerate, "LiDAR degenerate", diagnostic_msgs::DiagnosticStatus::WARN);
  flag(os::kMapTimeout, "map answer timed out", diagnostic_msgs::DiagnosticStatus::WARN);
  flag(os::kLidarFailed, "LiDAR update failed", diagnostic_msgs::DiagnosticStatus::ERROR);
  flag(os::kDegraded, "degraded (a consistency check is out of its bound)", diagnostic_msgs::DiagnosticStatus::WARN);
  flag(os::kLost, "LOST: the estimate is not trusted", diagnostic_msgs::DiagnosticStatus::ERROR);
  flag(os::kLidarUpdate, "LiDAR update", diagnostic_msgs::DiagnosticStatus::OK);
  flag(os::kVisualUpdate, "visual update", diagnostic_msgs::DiagnosticStatus::OK);
  d.message = msg.empty() ? "tracking" : msg;
  d.values.push_back(kv("utime", odo->utime));
  d.values.push_back(kv("status", odo->status));
  if (st) {
    d.values.push_back(kv("frame_index", st->frame_index));
    d.values.push_back(kv("lio_ms", st->lio_ms));
    d.values.push_back(kv("vio_ms", st->vio_ms));
    d.values.push_back(kv("map_ms", st->map_ms));
    d.values.push_back(kv("map_wait_ms", st->map_wait_ms));
    d.values.push_back(kv("total_ms", st->total_ms));
    d.values.push_back(kv("sigma_min", st->sigma_min));
    d.values.push_back(kv("degenerate", st->degenerate ? 1 : 0));
    d.values.push_back(kv("visual_used", st->visual_used ? 1 : 0));
    d.values.push_back(kv("map_timeout", st->map_timeout ? 1 : 0));
    d.values.push_back(kv("n_points", st->n_points));
    d.values.push_back(kv("n_planes_matched", st->n_planes_matched));
    d.values.push_back(kv("n_visual_points", st->n_visual_points));
    d.values.push_back(kv("dropped_points", st->dropped_points));
  }
  return d;
}

diagnostic_msgs::DiagnosticStatus mapServerStatus(const livo::MapStats* st) {
  diagnostic_msgs::DiagnosticStatus d;
  d.name = "livo: map server";
  d.hardware_id = "livo";
  if (!st) {
    d.level = diagnostic_msgs::DiagnosticStatus::STALE;
    d.message = "no map statistics (is livo-mapserver running?)";
    return d;
  }
  d.level = diagnostic_msgs::DiagnosticStatus::OK;
  char buf[128];
  std::snprintf(buf, sizeof buf, "%lld voxels, %.1f MiB%s", static_cast<long long>(st->local_voxels),
                static_cast<double>(st->bytes) / (1 << 20), st->bytes_cap > 0 ? " (capped)" : "");
  d.message = buf;
  d.values.push_back(kv("utime", st->utime));
  d.values.push_back(kv("local_voxels", st->local_voxels));
  d.values.push_back(kv("local_planes", st->local_planes));
  d.values.push_back(kv("visual_points_local", st->visual_points_local));
  d.values.push_back(kv("visual_points_longterm", st->visual_points_longterm));
  d.values.push_back(kv("bytes", st->bytes));
  d.values.push_back(kv("bytes_cap", st->bytes_cap));
  d.values.push_back(kv("evicted_visual_points", st->evicted_visual_points));
  d.values.push_back(kv("evicted_voxels", st->evicted_voxels));
  d.values.push_back(kv("slides", st->slides));
  d.values.push_back(kv("queries_answered", st->queries_answered));
  d.values.push_back(kv("last_slide_ms", st->last_slide_ms));
  return d;
}

}  // namespace livo_bridge
