// Reading ROS 1 bags (format 2.0; uncompressed, bz2 and lz4 chunks) through Debian's librosbag-storage.
// This header has no ROS types: the library stays inside rosbag_reader.cpp. Without the library (built
// without LIVO_HAVE_ROSBAG) every RosbagReader constructor throws a DatasetError saying so.
#pragma once

#include "livo/common/types.hpp"
#include "livo/datasets/conversion.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace livo {

/// True when the suite was built with ROS bag support (librosbag-storage-dev found).
bool rosbagSupported();

/// One topic of a bag (all its connections; they must agree on the type).
struct BagTopicInfo {
  std::string topic;
  std::string datatype;  ///< e.g. "sensor_msgs/Imu"
  std::string md5;       ///< MD5 of the message definition, from the connection record
  std::uint64_t messages = 0;
};

/// A bag read error (corrupt or truncated chunk, failed decompression).
struct BagReadError : DatasetError {
  using DatasetError::DatasetError;
};

/// One message handed to RosbagReader::forEach. The data buffer is reused between calls.
struct BagMessage {
  const std::string* topic = nullptr;
  Utime bag_time = 0;             ///< record time (when the recorder received it), microseconds
  std::uint64_t index = 0;        ///< 0-based position among the messages visited
  const std::vector<std::uint8_t>* data = nullptr;  ///< serialized message
};

class RosbagReader {
 public:
  /// Opens the bag and reads its index. Throws DatasetError naming the file for a missing file, an
  /// unindexed or truncated bag, or a build without bag support.
  explicit RosbagReader(const std::string& path);
  ~RosbagReader();
  RosbagReader(const RosbagReader&) = delete;
  RosbagReader& operator=(const RosbagReader&) = delete;

  const std::string& path() const { return path_; }
  /// Topics sorted by name. Throws DatasetError when one topic carries two different types.
  const std::vector<BagTopicInfo>& topics() const { return topics_; }
  /// Messages on these topics.
  std::uint64_t messageCount(const std::vector<std::string>& topics) const;

  /// Calls `fn` for every message on `topics` in record-time order until it returns false. A failure to
  /// read a message (corrupt chunk) throws BagReadError naming the topic, the message index and its
  /// record time (a record declaring more than 512 MiB counts as corrupt); exceptions thrown by `fn` pass
  /// through unchanged.
  void forEach(const std::vector<std::string>& topics, const std::function<bool(const BagMessage&)>& fn);

 private:
  struct Impl;
  std::string path_;
  std::unique_ptr<Impl> impl_;
  std::vector<BagTopicInfo> topics_;
};

}  // namespace livo
