// The estimator's outputs as ROS messages (pure conversions, no transport):
//   odometry_t -> nav_msgs/Odometry and a geometry_msgs/TransformStamped (world -> body);
//   registered_scan_t and the decimated map -> sensor_msgs/PointCloud2 (x, y, z, intensity float32, plus
//     rgb as a PCL-style packed float32 when the camera coloured the points; white where it did not);
//   estimator and map server statistics -> diagnostic_msgs/DiagnosticStatus.
// Pose covariance: odometry_t carries [rotation, position] with a right (body-frame) rotation perturbation,
// R = R_hat Exp(dtheta), and p = p_hat + dp in the world frame. nav_msgs/Odometry wants (x, y, z, rotation
// about the fixed X, Y, Z axes) of header.frame_id (the world): dtheta_world = R dtheta, so
//   C_ros = J C J^T with J = [[0, I], [R, 0]].
// Twist (child frame = body): linear = R^T v_world; odometry_t has no angular velocity and no velocity
// covariance, so angular is 0 and twist.covariance[0] = -1 (unknown, as sensor_msgs marks it).
#pragma once

#include "livo/io/estimator_messages.hpp"
#include "livo/io/map_messages.hpp"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstdint>
#include <string>

namespace livo_bridge {

/// Message time (us) -> ros::Time.
ros::Time rosTime(livo::Utime utime);

/// C_ros = J C J^T (header comment), row-major 6x6.
livo::Mat6 rosPoseCovariance(const livo::Mat3& R_world_imu, const livo::Mat6& cov_rot_pos);

nav_msgs::Odometry toRosOdometry(const livo::OdometryOutput& o, const std::string& world_frame,
                                 const std::string& body_frame);
geometry_msgs::TransformStamped toRosTransform(const livo::OdometryOutput& o, const std::string& world_frame,
                                               const std::string& body_frame);

/// Points as a PointCloud2 (unorganized, little-endian, dense). `rgb` may be null (no colour field).
void fillCloud(sensor_msgs::PointCloud2& out, std::size_t n, const float* x, const float* y, const float* z,
               const float* intensity, const std::int32_t* rgb);
/// The registered scan, in `world_frame`.
sensor_msgs::PointCloud2 toRosCloud(const livo::registered_scan_t& m, const std::string& world_frame);

/// Level and text of the estimator's status bits (odometry_t.status).
diagnostic_msgs::DiagnosticStatus estimatorStatus(const livo::OdometryOutput* odo, const livo::EstimatorStats* st);
diagnostic_msgs::DiagnosticStatus mapServerStatus(const livo::MapStats* st);

}  // namespace livo_bridge
