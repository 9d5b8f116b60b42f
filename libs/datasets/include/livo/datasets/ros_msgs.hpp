// Bounds-checked decoders of the ROS 1 messages that the bag converter reads, from their serialized bytes
// (ROS 1 wire format: little-endian, strings and variable arrays prefixed by a uint32 count, fixed arrays
// without). No ROS library is needed here: every declared length is checked against the bytes that remain
// before anything is allocated, and errors name the field, e.g.
// "sensor_msgs/PointCloud2.data: declares 4000000 bytes but 1200 remain".
//
// Time conventions (what each output message's utime is):
//   Imu, Image, CompressedImage: header.stamp, rounded to the nearest microsecond.
//   PointCloud2, Livox CustomMsg: scan start = the earliest point time, floored to the microsecond, where a
//     point time is header.stamp + the point's offset (or the point's absolute time, see below); every
//     point's time_offset_s is its time minus that start (>= 0). A cloud without a time field gets
//     utime = header.stamp and offsets 0.
// Per-point time fields of PointCloud2, looked up in this order unless one is named:
//   time (Velodyne), t (Ouster), timestamp (Hesai, Robosense, livox_ros_driver2), offset_time (Livox).
//   Unit: integer fields are nanoseconds; floating fields are seconds, except floating values of 1e15 and
//   more, which are nanoseconds (livox_ros_driver2 stores absolute ns in a float64).
//   Absolute or relative: when the largest |value| in the cloud is 1e5 s (about 28 h) or more, the values
//   are absolute times (the header stamp is then not used); otherwise they are offsets from header.stamp
//   (negative offsets, as old Velodyne drivers stamp the scan end, are fine).
// Livox CustomMsg: point time = header.stamp + offset_time (ns), as FAST-LIVO2 does; timebase is not used.
#pragma once

#include "livo/common/types.hpp"
#include "livo/datasets/conversion.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

namespace livo {

/// The ROS 1 message types the converter understands.
enum class RosType { Unknown, Imu, PointCloud2, LivoxCustomMsg, Image, CompressedImage };

/// RosType of a datatype string ("sensor_msgs/Imu"; "livox_ros_driver/CustomMsg" and
/// "livox_ros_driver2/CustomMsg" are both LivoxCustomMsg).
RosType rosTypeOf(const std::string& datatype);
/// MD5 sum of the message layout this decoder reads (as in the bag's connection records).
const char* rosLayoutMd5(RosType t);
/// Short list of the supported datatypes, for error messages.
const char* rosSupportedTypes();

/// Settings of the decoders.
struct RosDecodeOptions {
  std::string sensor = "generic";  ///< lidar_scan_t.sensor
  /// PointCloud2 per-point time field: "" = first present of time, t, timestamp, offset_time;
  /// "none" = no per-point times (offsets 0); any other name must exist in the cloud.
  std::string point_time_field;
  /// 16-bit mono images (mono16, 16UC1): 0 keeps them as GRAY16 (lossless, little-endian); 9..16 converts
  /// to GRAY8 as min(255, v >> (bits - 8)) for a camera with that many significant bits.
  int mono16_bits = 0;
  int max_image_side = 16384;  ///< pixels, width and height
};

/// What a LiDAR decoder produced besides the scan.
struct DecodedScan {
  LidarScan scan;
  Utime header_utime = 0;          ///< header.stamp, rounded to the microsecond
  std::int64_t span_ns = 0;        ///< latest - earliest point time
  std::size_t dropped_nonfinite = 0;
  std::string time_field;          ///< field used for point times ("" when none)
  bool absolute_times = false;     ///< the time field held absolute times
};

/// sensor_msgs/Imu -> sample (utime = header.stamp; orientation and covariances are not used).
ImuSample decodeRosImu(const std::uint8_t* data, std::size_t size);

/// sensor_msgs/PointCloud2 -> scan. x, y, z (float32 or float64) are required; intensity (else
/// reflectivity) and ring (else line) are read from any numeric type when present. Points with non-finite
/// coordinates are dropped and counted; big-endian clouds are byte-swapped.
DecodedScan decodeRosPointCloud2(const std::uint8_t* data, std::size_t size, const RosDecodeOptions& opt);

/// livox_ros_driver(2)/CustomMsg -> scan: intensity = reflectivity, ring = line; tags are not used.
DecodedScan decodeLivoxCustomMsg(const std::uint8_t* data, std::size_t size, const RosDecodeOptions& opt);

/// sensor_msgs/Image -> image: mono8/8UC1 -> GRAY8, rgb8 -> RGB8, bgr8/8UC3 -> BGR8, rgba8/bgra8 ->
/// RGB8/BGR8 (alpha dropped), mono16/16UC1 -> GRAY16 or GRAY8 (RosDecodeOptions::mono16_bits). Rows keep
/// the message's step as row_stride where no conversion is needed.
Image decodeRosImage(const std::uint8_t* data, std::size_t size, const RosDecodeOptions& opt);

/// sensor_msgs/CompressedImage -> JPEG or PNG image (recognised by the stream's magic bytes, the format
/// string is not trusted); width and height are read from the stream's header, the stream is kept as is.
Image decodeRosCompressedImage(const std::uint8_t* data, std::size_t size, const RosDecodeOptions& opt);

/// Size and format of a JPEG (SOF segment) or PNG (IHDR chunk) stream; false when it is neither or the
/// header is cut short.
bool compressedImageInfo(const std::uint8_t* data, std::size_t size, PixelFormat& format, int& width,
                         int& height);

/// header.stamp (sec, nsec) -> nanoseconds.
inline std::int64_t rosStampNs(std::uint32_t sec, std::uint32_t nsec) {
  return static_cast<std::int64_t>(sec) * 1'000'000'000 + nsec;
}
/// Nanoseconds -> microseconds, rounded to the nearest.
inline Utime nsToUtimeRound(std::int64_t ns) {
  return ns >= 0 ? (ns + 500) / 1000 : -((-ns + 500) / 1000);
}
/// Nanoseconds -> microseconds, rounded down (scan starts: every point offset stays >= 0).
inline Utime nsToUtimeFloor(std::int64_t ns) { return ns >= 0 ? ns / 1000 : -((-ns + 999) / 1000); }

}  // namespace livo
