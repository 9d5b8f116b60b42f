// Topic choice per role (ros_input.hpp), shared by the bag converter and the live bridge, and the bag
// converter's selection of all three roles.
#include "livo/datasets/ros_input.hpp"
#include "livo/datasets/rosbag.hpp"

#include <algorithm>

namespace livo {

namespace {

const char* roleTypeNames(RosRole role) {
  switch (role) {
    case RosRole::Lidar: return "sensor_msgs/PointCloud2 or livox_ros_driver(2)/CustomMsg";
    case RosRole::Imu: return "sensor_msgs/Imu";
    case RosRole::Camera: return "sensor_msgs/Image or sensor_msgs/CompressedImage";
  }
  return "";
}

std::string topicLine(const BagTopicInfo& t) {
  return "\n  " + t.topic + " (" + t.datatype + ", " + std::to_string(t.messages) + " messages)";
}

std::string topicList(const std::vector<BagTopicInfo>& topics) {
  std::string s;
  for (const auto& t : topics) s += topicLine(t);
  return s.empty() ? " none" : s;
}

}  // namespace

const char* roleName(RosRole role) {
  switch (role) {
    case RosRole::Lidar: return "LiDAR";
    case RosRole::Imu: return "IMU";
    case RosRole::Camera: return "camera";
  }
  return "";
}

const char* roleFlag(RosRole role) {
  switch (role) {
    case RosRole::Lidar: return "--lidar-topic";
    case RosRole::Imu: return "--imu-topic";
    case RosRole::Camera: return "--image-topic";
  }
  return "";
}

bool roleTakes(RosRole role, RosType type) {
  switch (role) {
    case RosRole::Lidar: return type == RosType::PointCloud2 || type == RosType::LivoxCustomMsg;
    case RosRole::Imu: return type == RosType::Imu;
    case RosRole::Camera: return type == RosType::Image || type == RosType::CompressedImage;
  }
  return false;
}

const std::string& roleTopicOption(const RosInputOptions& opt, RosRole role) {
  switch (role) {
    case RosRole::Lidar: return opt.lidar_topic;
    case RosRole::Imu: return opt.imu_topic;
    case RosRole::Camera: break;
  }
  return opt.image_topic;
}

RosTopicChoice chooseRosTopic(const std::vector<BagTopicInfo>& topics, RosRole role, const std::string& wanted,
                              const std::string& source) {
  using Kind = RosTopicChoice::Kind;
  RosTopicChoice c;
  if (wanted == "none") {
    c.kind = Kind::kSkipped;
    return c;
  }
  if (!wanted.empty()) {
    auto it = std::find_if(topics.begin(), topics.end(), [&](const BagTopicInfo& t) { return t.topic == wanted; });
    if (it == topics.end()) {
      c.kind = Kind::kMissing;
      c.problem = source + ": no topic " + wanted + " (" + roleFlag(role) + "); available topics:" + topicList(topics);
      return c;
    }
    c.type = rosTypeOf(it->datatype);
    if (!roleTakes(role, c.type)) {
      c.kind = Kind::kWrongType;
      c.problem = source + ": topic " + wanted + " has type " + it->datatype + ", which is not " +
                  (role == RosRole::Imu ? "an " : "a ") + roleName(role) + " type livo reads (" + roleTypeNames(role) +
                  "; supported types: " + rosSupportedTypes() + ")";
      return c;
    }
    c.kind = Kind::kChosen;
    c.topic = wanted;
    return c;
  }
  std::vector<const BagTopicInfo*> candidates;
  for (const auto& t : topics)
    if (roleTakes(role, rosTypeOf(t.datatype))) candidates.push_back(&t);
  if (candidates.size() > 1) {
    c.kind = Kind::kAmbiguous;
    c.problem = source + ": several " + roleName(role) + " topics; choose one with " + roleFlag(role) + " (or none):";
    for (const auto* t : candidates) c.problem += topicLine(*t);
    return c;
  }
  if (candidates.empty()) return c;  // kNoCandidate
  c.kind = Kind::kChosen;
  c.topic = candidates.front()->topic;
  c.type = rosTypeOf(candidates.front()->datatype);
  return c;
}

bool rosLayoutMatches(RosType type, const std::string& md5) { return md5 == "*" || md5 == rosLayoutMd5(type); }

RosbagTopics selectRosbagTopics(const std::vector<BagTopicInfo>& topics, const RosInputOptions& opt,
                                const std::string& bag_path) {
  RosbagTopics sel;
  for (RosRole role : {RosRole::Lidar, RosRole::Imu, RosRole::Camera}) {
    const RosTopicChoice c = chooseRosTopic(topics, role, roleTopicOption(opt, role), bag_path);
    if (!c.problem.empty()) throw DatasetError(c.problem);
    if (role == RosRole::Lidar) sel.lidar = c.topic, sel.lidar_type = c.type;
    if (role == RosRole::Imu) sel.imu = c.topic;
    if (role == RosRole::Camera) sel.image = c.topic, sel.image_type = c.type;
  }
  if (sel.lidar.empty() && sel.imu.empty() && sel.image.empty())
    throw DatasetError(bag_path + ": no LiDAR, IMU or camera topic to convert (supported types: " +
                       rosSupportedTypes() + "); topics in the bag:" + topicList(topics));
  for (const std::string* chosen : {&sel.lidar, &sel.imu, &sel.image}) {
    if (chosen->empty()) continue;
    for (const auto& t : topics) {
      const RosType type = rosTypeOf(t.datatype);
      if (t.topic == *chosen && !rosLayoutMatches(type, t.md5))
        throw DatasetError(bag_path + ": topic " + t.topic + ": " + t.datatype + " with definition MD5 " + t.md5 +
                           " is not the layout this converter reads (MD5 " + rosLayoutMd5(type) + ")");
    }
  }
  return sel;
}

}  // namespace livo
