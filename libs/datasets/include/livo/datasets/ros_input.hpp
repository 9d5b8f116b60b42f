// ROS 1 sensor input, the rules shared by the bag converter (`livo-convert rosbag`) and the live bridge
// (`livo-ros-bridge`): one implementation of what a topic, a message and an IMU stream become.
//
// Topics: each role (LiDAR, IMU, camera) takes the topic named in the options, or the only topic of a
// matching type (LiDAR: PointCloud2 or Livox CustomMsg; IMU: Imu; camera: Image or CompressedImage);
// "none" skips a role. chooseRosTopic() says what happened for one role; the converter turns every
// problem into an error before any output, the bridge waits for a missing topic and warns about the rest.
// Messages: RosDecoder applies the decoders of ros_msgs.hpp (times and layouts documented there) and the
// scan rules: empty scans and scans whose points span more than `max_scan_span_s` are skipped and counted.
// IMU acceleration unit (Livox IMUs report g): with `imu_accel_unit` Auto, the median |a| of the first
// `imu_unit_samples` decoded samples decides: 0.7..1.3 -> g (multiplied by `gravity_m_s2`), 7..13 -> m/s^2
// (kept), otherwise kept with a warning. ImuUnitGate holds the first samples of a stream that cannot look
// ahead until that decision (the converter reads them from the bag first).
#pragma once

#include "livo/datasets/ros_msgs.hpp"
#include "livo/datasets/rosbag_reader.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace livo {

enum class AccelUnit { Auto, G, MetresPerSecond2 };

/// What a ROS input (a bag or a live ROS graph) is read with.
struct RosInputOptions {
  std::string lidar_topic;  ///< "" = the only candidate, "none" = no LiDAR
  std::string imu_topic;
  std::string image_topic;
  std::string sensor;             ///< lidar_scan_t.sensor; "" = "avia" for Livox CustomMsg, else "generic"
  std::string point_time_field;   ///< RosDecodeOptions::point_time_field
  int mono16_bits = 0;            ///< RosDecodeOptions::mono16_bits
  AccelUnit imu_accel_unit = AccelUnit::Auto;
  int imu_unit_samples = 200;     ///< samples for the unit detection
  double gravity_m_s2 = 9.80665;  ///< m/s^2 per g (standard gravity)
  double max_scan_span_s = 1.0;   ///< s; scans whose points span more are skipped (wrong time unit?)
};

/// Throws DatasetError naming the flag of a value out of range.
void checkRosInputOptions(const RosInputOptions& opt);

// ---- topics ----

enum class RosRole { Lidar, Imu, Camera };
const char* roleName(RosRole role);  ///< "LiDAR", "IMU", "camera"
const char* roleFlag(RosRole role);  ///< "--lidar-topic", ...
/// True when messages of `type` can feed `role`.
bool roleTakes(RosRole role, RosType type);
/// The option naming the role's topic.
const std::string& roleTopicOption(const RosInputOptions& opt, RosRole role);

/// The outcome of choosing the topic of one role.
struct RosTopicChoice {
  enum class Kind {
    kChosen,       ///< `topic` (of `type`)
    kSkipped,      ///< "none" was asked for
    kNoCandidate,  ///< nothing named, no topic of a matching type
    kMissing,      ///< the named topic does not exist (yet)
    kWrongType,    ///< the named topic's type is not one of the role's (or not known at all)
    kAmbiguous,    ///< nothing named, several topics of a matching type
  };
  Kind kind = Kind::kNoCandidate;
  std::string topic;
  RosType type = RosType::Unknown;
  std::string problem;  ///< kMissing, kWrongType, kAmbiguous: names the topics, the flag and the candidates
};

/// Chooses the topic of `role` among `topics` (a bag's, or the published topics of a ROS master, with
/// `messages` 0 when unknown). `source` starts every problem text (the bag's path, "ROS master").
RosTopicChoice chooseRosTopic(const std::vector<BagTopicInfo>& topics, RosRole role, const std::string& wanted,
                              const std::string& source);

/// True when `md5` (a bag connection's or a publisher's) is the layout the decoder of `type` reads ("*"
/// matches anything: the writer did not say).
bool rosLayoutMatches(RosType type, const std::string& md5);

// ---- messages ----

/// One decoded message: an IMU sample, a scan or an image.
using RosPayload = std::variant<ImuSample, LidarScan, Image>;
inline Utime payloadUtime(const RosPayload& p) {
  return std::visit([](const auto& v) { return v.utime; }, p);
}

/// What the scan rules skipped or noticed.
struct RosDecodeCounts {
  std::uint64_t empty_scans = 0, long_scans = 0, untimed_scans = 0, nonfinite_points = 0;
  std::string long_example;  ///< the first long scan: "points span 2.5 s (time field 't')"
};

/// Decodes serialized messages by type with the scan rules (header comment). Not thread-safe: one per
/// thread (the counts are its only state).
class RosDecoder {
 public:
  /// Throws DatasetError for options out of range (checkRosInputOptions).
  explicit RosDecoder(const RosInputOptions& opt);
  /// Decodes one message of `type` (Unknown throws). nullopt: a scan rule skipped it (counted). Throws
  /// DatasetError naming the field for a malformed message. IMU samples come unscaled (ImuUnitGate).
  std::optional<RosPayload> decode(RosType type, const std::uint8_t* data, std::size_t size);
  const RosDecodeCounts& counts() const { return counts_; }

 private:
  std::optional<RosPayload> scan(DecodedScan ds);
  RosInputOptions opt_;
  RosDecodeOptions generic_, livox_;  ///< livox_: the Livox default sensor name
  std::int64_t max_span_ns_ = 0;
  RosDecodeCounts counts_;
};

/// Scale for IMU accelerations from the median |a| of samples (rule above); `note` explains the choice.
double detectAccelScale(const std::vector<double>& accel_norms, const RosInputOptions& opt, std::string& note);

/// The IMU unit decision for a stream: with AccelUnit Auto, samples are held until `imu_unit_samples`
/// have come (or finish()), then the unit is decided and every held sample is released, scaled; later
/// samples pass at once. With G or MetresPerSecond2 nothing is held.
class ImuUnitGate {
 public:
  explicit ImuUnitGate(const RosInputOptions& opt);
  /// Takes one decoded (unscaled) sample; appends the samples now ready, scaled, to `ready`.
  void push(const ImuSample& s, std::vector<ImuSample>& ready);
  /// Decides with the samples held so far (the stream ended) and releases them into `ready`.
  void finish(std::vector<ImuSample>& ready);
  bool decided() const { return decided_; }
  double scale() const { return scale_; }
  const std::string& note() const { return note_; }
  std::size_t held() const { return held_.size(); }

 private:
  void decide(std::vector<ImuSample>& ready);
  RosInputOptions opt_;
  bool decided_ = false;
  double scale_ = 1.0;
  std::string note_;
  std::vector<ImuSample> held_;
};

}  // namespace livo
