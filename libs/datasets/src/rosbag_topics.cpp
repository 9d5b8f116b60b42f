// Topic selection for the bag converter and the IMU acceleration unit rule (rosbag.hpp).
#include "livo/datasets/rosbag.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace livo {

namespace {

struct Role {
  const char* name;    ///< "LiDAR"
  const char* flag;    ///< "--lidar-topic"
  std::vector<RosType> types;
  const char* type_names;
};

std::string topicList(const std::vector<BagTopicInfo>& topics) {
  std::string s;
  for (const auto& t : topics)
    s += "\n  " + t.topic + " (" + t.datatype + ", " + std::to_string(t.messages) + " messages)";
  return s.empty() ? " none" : s;
}

bool hasRoleType(const Role& role, const std::string& datatype) {
  const RosType t = rosTypeOf(datatype);
  return std::find(role.types.begin(), role.types.end(), t) != role.types.end();
}

/// The topic for one role, "" for none.
std::string pick(const std::vector<BagTopicInfo>& topics, const Role& role, const std::string& wanted,
                 const std::string& bag) {
  if (wanted == "none") return "";
  if (!wanted.empty()) {
    auto it = std::find_if(topics.begin(), topics.end(), [&](const BagTopicInfo& t) { return t.topic == wanted; });
    if (it == topics.end())
      throw DatasetError(bag + ": no topic " + wanted + " (" + role.flag + "); topics in the bag:" + topicList(topics));
    if (!hasRoleType(role, it->datatype))
      throw DatasetError(bag + ": topic " + wanted + " has type " + it->datatype + ", which is not a " + role.name +
                         " type this converter reads (" + role.type_names + "; supported types: " +
                         rosSupportedTypes() + ")");
    return wanted;
  }
  std::vector<const BagTopicInfo*> candidates;
  for (const auto& t : topics)
    if (hasRoleType(role, t.datatype)) candidates.push_back(&t);
  if (candidates.size() > 1) {
    std::string names;
    for (const auto* c : candidates)
      names += "\n  " + c->topic + " (" + c->datatype + ", " + std::to_string(c->messages) + " messages)";
    throw DatasetError(bag + ": several " + role.name + " topics; choose one with " + role.flag + " (or none):" + names);
  }
  return candidates.empty() ? "" : candidates.front()->topic;
}

void checkLayout(const std::vector<BagTopicInfo>& topics, const std::string& topic, const std::string& bag) {
  if (topic.empty()) return;
  for (const auto& t : topics) {
    if (t.topic != topic) continue;
    const char* known = rosLayoutMd5(rosTypeOf(t.datatype));
    if (t.md5 != known && t.md5 != "*")
      throw DatasetError(bag + ": topic " + topic + ": " + t.datatype + " with definition MD5 " + t.md5 +
                         " is not the layout this converter reads (MD5 " + known + ")");
  }
}

RosType typeOf(const std::vector<BagTopicInfo>& topics, const std::string& topic) {
  for (const auto& t : topics)
    if (t.topic == topic) return rosTypeOf(t.datatype);
  return RosType::Unknown;
}

}  // namespace

RosbagTopics selectRosbagTopics(const std::vector<BagTopicInfo>& topics, const RosbagOptions& opt,
                                const std::string& bag_path) {
  const Role lidar{"LiDAR", "--lidar-topic", {RosType::PointCloud2, RosType::LivoxCustomMsg},
                   "sensor_msgs/PointCloud2 or livox_ros_driver(2)/CustomMsg"};
  const Role imu{"IMU", "--imu-topic", {RosType::Imu}, "sensor_msgs/Imu"};
  const Role camera{"camera", "--image-topic", {RosType::Image, RosType::CompressedImage},
                    "sensor_msgs/Image or sensor_msgs/CompressedImage"};
  RosbagTopics sel;
  sel.lidar = pick(topics, lidar, opt.lidar_topic, bag_path);
  sel.imu = pick(topics, imu, opt.imu_topic, bag_path);
  sel.image = pick(topics, camera, opt.image_topic, bag_path);
  if (sel.lidar.empty() && sel.imu.empty() && sel.image.empty())
    throw DatasetError(bag_path + ": no LiDAR, IMU or camera topic to convert (supported types: " +
                       rosSupportedTypes() + "); topics in the bag:" + topicList(topics));
  for (const std::string* t : {&sel.lidar, &sel.imu, &sel.image}) checkLayout(topics, *t, bag_path);
  sel.lidar_type = typeOf(topics, sel.lidar);
  sel.image_type = typeOf(topics, sel.image);
  return sel;
}

double detectAccelScale(const std::vector<double>& accel_norms, const RosbagOptions& opt, std::string& note) {
  char buf[200];
  if (opt.imu_accel_unit == AccelUnit::G) {
    std::snprintf(buf, sizeof buf, "acceleration in g (--imu-accel-unit g): multiplied by %.5f", opt.gravity_m_s2);
    note = buf;
    return opt.gravity_m_s2;
  }
  if (opt.imu_accel_unit == AccelUnit::MetresPerSecond2 || accel_norms.empty()) {
    note = accel_norms.empty() ? "no IMU samples: acceleration unit not checked" : "acceleration in m/s^2 (given)";
    return 1.0;
  }
  std::vector<double> v = accel_norms;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  const double median = v[v.size() / 2];
  if (median >= 0.7 && median <= 1.3) {
    std::snprintf(buf, sizeof buf, "acceleration in g detected (median |a| %.3f over %zu samples): multiplied by %.5f",
                  median, v.size(), opt.gravity_m_s2);
    note = buf;
    return opt.gravity_m_s2;
  }
  if (median >= 7.0 && median <= 13.0)
    std::snprintf(buf, sizeof buf, "acceleration in m/s^2 (median |a| %.3f over %zu samples)", median, v.size());
  else
    std::snprintf(buf, sizeof buf,
                  "WARNING: median |a| %.3f over %zu samples is neither about 1 g nor about 9.8 m/s^2: kept as is",
                  median, v.size());
  note = buf;
  return 1.0;
}

}  // namespace livo
