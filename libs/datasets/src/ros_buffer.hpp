// Private: a bounds-checked cursor over one serialized ROS 1 message (little-endian). Every read checks the
// bytes that remain; array and string lengths are checked against them before the caller allocates.
#pragma once

#include "livo/datasets/conversion.hpp"

#include <cstdint>
#include <cstring>
#include <string>

namespace livo {

class RosBuffer {
 public:
  RosBuffer(const std::uint8_t* data, std::size_t size, const char* type) : p_(data), n_(size), type_(type) {}

  std::size_t remaining() const { return n_ - pos_; }
  std::size_t size() const { return n_; }

  [[noreturn]] void fail(const char* field, const std::string& what) const {
    throw DatasetError(std::string(type_) + "." + field + ": " + what);
  }

  /// Fixed-size value of type T (uint8..uint64, float, double).
  template <class T>
  T get(const char* field) {
    need(sizeof(T), field);
    T v;
    std::memcpy(&v, p_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }

  /// Pointer to `bytes` bytes at the cursor, then skips them.
  const std::uint8_t* take(std::size_t bytes, const char* field) {
    need(bytes, field);
    const std::uint8_t* q = p_ + pos_;
    pos_ += bytes;
    return q;
  }

  /// uint32 length prefix of a variable array whose elements take at least `elem_bytes` each; checked
  /// against the bytes that remain.
  std::uint32_t count(const char* field, std::size_t elem_bytes) {
    const auto n = get<std::uint32_t>(field);
    if (elem_bytes > 0 && static_cast<std::uint64_t>(n) * elem_bytes > remaining())
      fail(field, "declares " + std::to_string(n) + " elements of " + std::to_string(elem_bytes) +
                      " bytes but " + std::to_string(remaining()) + " bytes remain");
    return n;
  }

  /// Length-prefixed byte array (uint8[] / string payload).
  const std::uint8_t* bytes(const char* field, std::uint32_t& len) {
    len = get<std::uint32_t>(field);
    if (len > remaining())
      fail(field, "declares " + std::to_string(len) + " bytes but " + std::to_string(remaining()) + " remain");
    return take(len, field);
  }

  std::string string(const char* field) {
    std::uint32_t len = 0;
    const std::uint8_t* s = bytes(field, len);
    return std::string(reinterpret_cast<const char*>(s), len);
  }

  /// The message must end here: trailing bytes mean another layout than the one decoded.
  void finish() const {
    if (remaining() != 0)
      fail("(end)", std::to_string(remaining()) + " unexpected bytes after the last field (message of " +
                        std::to_string(n_) + " bytes): not the layout this decoder reads");
  }

  /// std_msgs/Header: seq, stamp (sec, nsec), frame_id. Returns the stamp in nanoseconds.
  std::int64_t header() {
    get<std::uint32_t>("header.seq");
    const auto sec = get<std::uint32_t>("header.stamp.sec");
    const auto nsec = get<std::uint32_t>("header.stamp.nsec");
    if (nsec >= 1'000'000'000u) fail("header.stamp.nsec", std::to_string(nsec) + " is not below 1e9");
    std::uint32_t len = 0;
    bytes("header.frame_id", len);
    return static_cast<std::int64_t>(sec) * 1'000'000'000 + nsec;
  }

 private:
  void need(std::size_t bytes, const char* field) const {
    if (bytes > remaining())
      fail(field, "message ends early (needs " + std::to_string(bytes) + " more bytes, " +
                      std::to_string(remaining()) + " remain of " + std::to_string(n_) + ")");
  }

  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
  const char* type_;
};

}  // namespace livo
