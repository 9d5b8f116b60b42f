// A roscpp message type for "any type", decoded where roscpp received it: roscpp hands the serialized
// bytes of each message to Serializer<RosWireMessage>::read in the subscription's callback thread, which
// passes them to the subscription's WireDecoder (the suite's ROS decoders, libs/datasets). The raw message
// is never copied and no roscpp message object is built: the decoded scan, image or IMU sample is all
// that is kept. Subscribed with MD5 and type "*", like topic_tools::ShapeShifter; the publisher's real type
// and layout MD5 come from the connection header and are checked before decoding.
#pragma once

#include "livo/datasets/ros_input.hpp"

#include <ros/message_traits.h>
#include <ros/serialization.h>

#include <boost/shared_ptr.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace livo_bridge {

struct RosWireMessage;

/// Decodes the bytes of one message into it (never throws: failures are recorded in the message).
class WireDecoder {
 public:
  virtual ~WireDecoder() = default;
  virtual void decodeInto(RosWireMessage& m, const std::uint8_t* data, std::size_t size) = 0;
};

struct RosWireMessage {
  WireDecoder* decoder = nullptr;  ///< set by the subscription's create function
  boost::shared_ptr<std::map<std::string, std::string>> connection_header;  ///< the publisher's ("type", "md5sum")
  std::size_t bytes = 0;           ///< serialized size
  double decode_ms = 0;
  /// The decoded message; the one callback of the subscription moves it out (hence mutable).
  mutable std::optional<livo::RosPayload> payload;
  enum class Reject { kNone, kType, kDecode } reject = Reject::kNone;
  std::string error;  ///< why it was rejected

  std::string header(const char* key) const {
    if (!connection_header) return "";
    auto it = connection_header->find(key);
    return it == connection_header->end() ? "" : it->second;
  }
};

}  // namespace livo_bridge

namespace ros {
namespace message_traits {
template <>
struct MD5Sum<livo_bridge::RosWireMessage> {
  static const char* value() { return "*"; }
  static const char* value(const livo_bridge::RosWireMessage&) { return "*"; }
};
template <>
struct DataType<livo_bridge::RosWireMessage> {
  static const char* value() { return "*"; }
  static const char* value(const livo_bridge::RosWireMessage&) { return "*"; }
};
template <>
struct Definition<livo_bridge::RosWireMessage> {
  static const char* value() { return ""; }
  static const char* value(const livo_bridge::RosWireMessage&) { return ""; }
};
}  // namespace message_traits

namespace serialization {
template <>
struct Serializer<livo_bridge::RosWireMessage> {
  template <typename Stream>
  static void read(Stream& stream, livo_bridge::RosWireMessage& m) {
    m.bytes = stream.getLength();
    if (m.decoder) m.decoder->decodeInto(m, stream.getData(), stream.getLength());
  }
  template <typename Stream>
  static void write(Stream&, const livo_bridge::RosWireMessage&) {}  // only ever received
  static std::uint32_t serializedLength(const livo_bridge::RosWireMessage&) { return 0; }
};

template <>
struct PreDeserialize<livo_bridge::RosWireMessage> {
  static void notify(const PreDeserializeParams<livo_bridge::RosWireMessage>& params) {
    params.message->connection_header = params.connection_header;
  }
};
}  // namespace serialization
}  // namespace ros
