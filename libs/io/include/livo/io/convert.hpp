// Conversions between plain structs (livo/common/types.hpp) and LCM messages, with validation.
//
// Decoding never trusts a count inside a message: `decode()` first walks the raw bytes and checks every
// declared count against the bytes that remain and against MessageLimits, and only then lets the
// generated code allocate. Validation errors name the field, e.g.
// "lidar_scan_t.num_points: declared 5000 but x has 4999 values".
#pragma once

#include "livo/common/types.hpp"

#include <livo/frame_t.hpp>
#include <livo/image_t.hpp>
#include <livo/imu_t.hpp>
#include <livo/lidar_scan_t.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace livo {

/// Upper bounds for counts and sizes inside messages (configurable, checked before allocating).
struct MessageLimits {
  std::int64_t max_message_bytes = 256ll << 20;  ///< whole encoded message
  std::int32_t max_points = 2'000'000;           ///< points per scan / sweep / registered scan
  std::int32_t max_image_side = 16384;           ///< pixels, width and height
  std::int32_t max_imu_per_frame = 20'000;
  std::int32_t max_planes = 2'000'000;
  std::int32_t max_visual_points = 1'000'000;
  std::int32_t max_patch_values = 4096;          ///< floats per stored patch pyramid
  std::int32_t max_patches_per_point = 64;
  std::int32_t max_keyframes = 1'000'000;       ///< keyframes / loop edges per map correction
};

/// Result of a validation: empty `error` means valid.
struct Validation {
  std::string error;
  explicit operator bool() const { return error.empty(); }
  static Validation ok() { return {}; }
  static Validation fail(std::string e) { return Validation{std::move(e)}; }
};

// ---- struct -> message (always valid input assumed; counts are set from the vectors) ----
livo::imu_t toMsg(const ImuSample& s);
livo::lidar_scan_t toMsg(const LidarScan& s);
livo::image_t toMsg(const Image& img);
/// The pixels move into the message (no copy); `img` is left without data.
livo::image_t toMsg(Image&& img);
livo::frame_t toMsg(const Frame& f);

// ---- message -> struct, with validation (finite values, counts match arrays, sizes sane) ----
Validation fromMsg(const livo::imu_t& m, ImuSample& out);
/// Points with non-finite coordinates are dropped (not an error) and counted in `*dropped_nonfinite`.
Validation fromMsg(const livo::lidar_scan_t& m, LidarScan& out, const MessageLimits& lim = {},
                   std::size_t* dropped_nonfinite = nullptr);
Validation fromMsg(const livo::image_t& m, Image& out, const MessageLimits& lim = {});
/// The pixels move out of the message (no copy of a frame's worth of bytes); `m` is left without data.
Validation fromMsg(livo::image_t&& m, Image& out, const MessageLimits& lim = {});
Validation fromMsg(const livo::frame_t& m, Frame& out, const MessageLimits& lim = {},
                   std::size_t* dropped_nonfinite = nullptr);

// ---- validation of decoded messages (used by fromMsg; exposed for processes and tests) ----
Validation validate(const livo::imu_t& m);
Validation validate(const livo::lidar_scan_t& m, const MessageLimits& lim = {});
Validation validate(const livo::image_t& m, const MessageLimits& lim = {});
Validation validate(const livo::frame_t& m, const MessageLimits& lim = {});

/// Checks the raw encoding of a message of type Msg (fingerprint, every declared count against the
/// remaining bytes and the limits) without allocating. Specialised for every livo type.
template <class Msg>
Validation precheck(const void* data, std::size_t size, const MessageLimits& lim = {});

/// precheck() then the generated decode(); on success `out` holds the message.
template <class Msg>
Validation decode(const void* data, std::size_t size, Msg& out, const MessageLimits& lim = {});

/// Encodes any generated message into a byte buffer.
template <class Msg>
std::vector<std::uint8_t> encode(const Msg& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

}  // namespace livo
