// RosbagReader on librosbag-storage (the only file that includes ROS headers), or a stub that reports a
// build without bag support.
#include "livo/datasets/rosbag_reader.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>

#ifdef LIVO_HAVE_ROSBAG
#include <rosbag/bag.h>
#include <rosbag/view.h>
#endif

namespace livo {

#ifdef LIVO_HAVE_ROSBAG

namespace {
constexpr std::uint32_t kMaxMessageBytes = 512u << 20;  // larger records are taken as corrupt

std::string seconds(Utime t) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", toSeconds(t));
  return buf;
}
}  // namespace

bool rosbagSupported() { return true; }

struct RosbagReader::Impl {
  rosbag::Bag bag;
};

RosbagReader::RosbagReader(const std::string& path) : path_(path), impl_(std::make_unique<Impl>()) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw DatasetError(path + ": no such file");
  const auto file_bytes = std::filesystem::file_size(path, ec);
  try {
    impl_->bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagUnindexedException&) {
    throw DatasetError(path + ": the bag has no index (recording interrupted?): run `rosbag reindex` on it first");
  } catch (const std::exception& e) {
    throw DatasetError(path + ": cannot read the bag (" + e.what() + "; " + std::to_string(file_bytes) +
                       " bytes): truncated or not a ROS 1 bag (format 2.0)? A cut-off recording can be repaired "
                       "with `rosbag reindex`");
  }
  try {
    rosbag::View all(impl_->bag);
    std::map<std::string, BagTopicInfo> by_topic;
    for (const rosbag::ConnectionInfo* c : all.getConnections()) {
      BagTopicInfo& t = by_topic[c->topic];
      if (t.topic.empty()) {
        t.topic = c->topic;
        t.datatype = c->datatype;
        t.md5 = c->md5sum;
      } else if (t.datatype != c->datatype || t.md5 != c->md5sum) {
        throw DatasetError(path + ": topic " + c->topic + " carries two types (" + t.datatype + " and " +
                           c->datatype + ")");
      }
    }
    for (auto& [name, t] : by_topic) {
      rosbag::View v(impl_->bag, rosbag::TopicQuery(name));
      t.messages = v.size();
      topics_.push_back(t);
    }
  } catch (const DatasetError&) {
    throw;
  } catch (const std::exception& e) {
    throw DatasetError(path + ": cannot read the bag's index (" + e.what() + ")");
  }
}

RosbagReader::~RosbagReader() = default;

std::uint64_t RosbagReader::messageCount(const std::vector<std::string>& topics) const {
  std::uint64_t n = 0;
  for (const auto& t : topics_)
    if (std::find(topics.begin(), topics.end(), t.topic) != topics.end()) n += t.messages;
  return n;
}

void RosbagReader::forEach(const std::vector<std::string>& topics, const std::function<bool(const BagMessage&)>& fn) {
  if (topics.empty()) return;
  rosbag::View view(impl_->bag, rosbag::TopicQuery(topics));
  std::vector<std::uint8_t> buf;
  BagMessage m;
  m.data = &buf;
  std::string topic;
  m.topic = &topic;
  for (auto it = view.begin(); it != view.end(); ++m.index) {
    const rosbag::MessageInstance& mi = *it;
    topic = mi.getTopic();
    m.bag_time = static_cast<Utime>(mi.getTime().sec) * 1'000'000 + mi.getTime().nsec / 1000;
    try {
      const std::uint32_t size = mi.size();
      if (size > kMaxMessageBytes)
        throw std::runtime_error("the record declares " + std::to_string(size) + " bytes (limit " +
                                 std::to_string(kMaxMessageBytes) + ")");
      buf.resize(size);
      ros::serialization::OStream stream(buf.data(), static_cast<std::uint32_t>(buf.size()));
      mi.write(stream);
    } catch (const std::exception& e) {
      throw BagReadError(path_ + ": cannot read message " + std::to_string(m.index) + " (topic " + topic +
                         ", record time " + seconds(m.bag_time) + " s): " + e.what() +
                         " -- corrupt or truncated chunk");
    }
    if (!fn(m)) return;
    try {
      ++it;
    } catch (const std::exception& e) {
      throw BagReadError(path_ + ": cannot read past message " + std::to_string(m.index) + " (topic " + topic +
                         ", record time " + seconds(m.bag_time) + " s): " + e.what());
    }
  }
}

#else  // no librosbag-storage

bool rosbagSupported() { return false; }

struct RosbagReader::Impl {};

RosbagReader::RosbagReader(const std::string& path) : path_(path) {
  throw DatasetError(path + ": this build has no ROS bag support (librosbag-storage-dev was not found, or "
                            "LIVO_WITH_ROSBAG was OFF, when it was configured): install it (scripts/setup does) and rebuild");
}

RosbagReader::~RosbagReader() = default;

std::uint64_t RosbagReader::messageCount(const std::vector<std::string>&) const { return 0; }

void RosbagReader::forEach(const std::vector<std::string>&, const std::function<bool(const BagMessage&)>&) {}

#endif

}  // namespace livo
