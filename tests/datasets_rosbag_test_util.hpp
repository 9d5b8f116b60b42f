// Shared helpers of the ROS bag import tests (tests/test_datasets_rosbag_*.cpp): a temporary folder, ROS
// time and rounding oracles, hand-serialized messages (Livox CustomMsg, any type with made-up bytes),
// sensor_msgs builders (IMU, PointCloud2 from a field layout), an IMU-only bag writer and the LCM log
// read back. LIVO_TEST_ROSBAG is 1 when the bag writers can be built (librosbag-storage and sensor_msgs).
#pragma once

#include "livo/datasets/rosbag.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/log.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#if !defined(LIVO_HAVE_ROSBAG) || !__has_include(<sensor_msgs/Imu.h>)
#define LIVO_TEST_ROSBAG 0
#else
#define LIVO_TEST_ROSBAG 1

#include <rosbag/bag.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <random>

namespace fs = std::filesystem;

// ---- a message of any type with hand-made bytes (Livox CustomMsg, unknown types, wrong MD5) ----
struct RawMsg {
  std::string datatype, md5, definition = "# test\n";
  std::vector<std::uint8_t> bytes;
};
namespace ros {
namespace message_traits {
template <>
struct MD5Sum<RawMsg> {
  static const char* value(const RawMsg& m) { return m.md5.c_str(); }
};
template <>
struct DataType<RawMsg> {
  static const char* value(const RawMsg& m) { return m.datatype.c_str(); }
};
template <>
struct Definition<RawMsg> {
  static const char* value(const RawMsg& m) { return m.definition.c_str(); }
};
}  // namespace message_traits
namespace serialization {
template <>
struct Serializer<RawMsg> {
  template <typename Stream>
  static void write(Stream& s, const RawMsg& m) {
    if (!m.bytes.empty()) std::memcpy(s.advance(static_cast<std::uint32_t>(m.bytes.size())), m.bytes.data(), m.bytes.size());
  }
  static std::uint32_t serializedLength(const RawMsg& m) { return static_cast<std::uint32_t>(m.bytes.size()); }
};
}  // namespace serialization
}  // namespace ros
namespace livo::test {

struct TempDir {
  fs::path path;
  TempDir() {
    static int counter = 0;
    path = fs::temp_directory_path() / ("livo_test_rosbag_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

inline constexpr std::int64_t kT0 = 1'650'000'000'000'000'000;  // ns, a 2022 Unix time

inline ros::Time rosTime(std::int64_t ns) {
  return ros::Time(static_cast<std::uint32_t>(ns / 1'000'000'000), static_cast<std::uint32_t>(ns % 1'000'000'000));
}
/// Independent oracles of the documented rounding rules.
inline Utime roundUs(std::int64_t ns) { return static_cast<Utime>(std::llround(static_cast<long double>(ns) / 1000)); }
inline Utime floorUs(std::int64_t ns) { return static_cast<Utime>(std::floor(static_cast<long double>(ns) / 1000)); }

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

template <class F>
inline std::string errorOf(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

/// Little-endian byte writer for hand-serialized messages.
struct Bytes {
  std::vector<std::uint8_t> b;
  template <class T>
  Bytes& put(T v) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    b.insert(b.end(), p, p + sizeof(T));
    return *this;
  }
  Bytes& str(const std::string& s) {
    put<std::uint32_t>(static_cast<std::uint32_t>(s.size()));
    b.insert(b.end(), s.begin(), s.end());
    return *this;
  }
  Bytes& header(std::int64_t stamp_ns, const std::string& frame = "f") {
    put<std::uint32_t>(7).put<std::uint32_t>(static_cast<std::uint32_t>(stamp_ns / 1'000'000'000));
    put<std::uint32_t>(static_cast<std::uint32_t>(stamp_ns % 1'000'000'000));
    return str(frame);
  }
};

struct LivoxPoint {
  std::uint32_t offset_ns;
  float x, y, z;
  std::uint8_t reflectivity, tag, line;
};

inline RawMsg livoxMsg(const std::string& datatype, std::int64_t stamp_ns, const std::vector<LivoxPoint>& pts) {
  Bytes w;
  w.header(stamp_ns).put<std::uint64_t>(static_cast<std::uint64_t>(stamp_ns)).put<std::uint32_t>(pts.size());
  w.put<std::uint8_t>(1).put<std::uint8_t>(0).put<std::uint8_t>(0).put<std::uint8_t>(0);
  w.put<std::uint32_t>(pts.size());
  for (const auto& p : pts)
    w.put(p.offset_ns).put(p.x).put(p.y).put(p.z).put(p.reflectivity).put(p.tag).put(p.line);
  return RawMsg{datatype, rosLayoutMd5(RosType::LivoxCustomMsg), "# livox\n", w.b};
}

inline sensor_msgs::Imu imuMsg(std::int64_t stamp_ns, const Eigen::Vector3d& gyro, const Eigen::Vector3d& acc) {
  sensor_msgs::Imu m;
  m.header.stamp = rosTime(stamp_ns);
  m.header.frame_id = "imu";
  m.orientation.w = 1;
  m.angular_velocity.x = gyro.x(), m.angular_velocity.y = gyro.y(), m.angular_velocity.z = gyro.z();
  m.linear_acceleration.x = acc.x(), m.linear_acceleration.y = acc.y(), m.linear_acceleration.z = acc.z();
  return m;
}

struct ReadBack {
  std::vector<ImuSample> imu;
  std::vector<LidarScan> scans;
  std::vector<Image> images;
  std::vector<Utime> times;  ///< log timestamps in file order
};

inline ReadBack readLog(const std::string& path) {
  ReadBack r;
  LogReader reader(path);
  LogEvent ev;
  while (reader.next(ev)) {
    r.times.push_back(ev.timestamp);
    Utime utime = 0;
    if (ev.channel == "LIVO_IMU") {
      imu_t m;
      EXPECT_TRUE(decode(ev.data.data(), ev.data.size(), m));
      r.imu.emplace_back();
      EXPECT_TRUE(fromMsg(m, r.imu.back()));
      utime = m.utime;
    } else if (ev.channel == "LIVO_LIDAR") {
      lidar_scan_t m;
      EXPECT_TRUE(decode(ev.data.data(), ev.data.size(), m));
      r.scans.emplace_back();
      EXPECT_TRUE(fromMsg(m, r.scans.back()));
      utime = m.utime;
    } else if (ev.channel == "LIVO_CAMERA") {
      image_t m;
      EXPECT_TRUE(decode(ev.data.data(), ev.data.size(), m));
      r.images.emplace_back();
      EXPECT_TRUE(fromMsg(m, r.images.back()));
      utime = m.utime;
    } else {
      ADD_FAILURE() << "unexpected channel " << ev.channel;
    }
    EXPECT_EQ(utime, ev.timestamp) << ev.channel;
  }
  return r;
}

inline RosbagOptions only(const std::string& lidar, const std::string& imu, const std::string& image) {
  RosbagOptions o;
  o.lidar_topic = lidar, o.imu_topic = imu, o.image_topic = image;
  return o;
}


// ---- PointCloud2 built from a field layout (values packed by the test, envelope by ROS) ----
struct FieldSpec {
  std::string name;
  std::uint8_t type;  // sensor_msgs::PointField constants
  std::uint32_t offset;
};
struct CloudSpec {
  std::string name;
  std::vector<FieldSpec> fields;
  std::uint32_t point_step;
  std::uint32_t height = 1;
  bool big_endian = false;
};
using PointValues = std::map<std::string, double>;

template <class T>
inline void packAs(std::uint8_t* dst, double v, bool big_endian) {
  const T t = static_cast<T>(v);
  std::memcpy(dst, &t, sizeof(T));
  if (big_endian) std::reverse(dst, dst + sizeof(T));
}

inline void pack(std::uint8_t* dst, std::uint8_t type, double v, bool be) {
  using F = sensor_msgs::PointField;
  switch (type) {
    case F::INT8: return packAs<std::int8_t>(dst, v, be);
    case F::UINT8: return packAs<std::uint8_t>(dst, v, be);
    case F::INT16: return packAs<std::int16_t>(dst, v, be);
    case F::UINT16: return packAs<std::uint16_t>(dst, v, be);
    case F::INT32: return packAs<std::int32_t>(dst, v, be);
    case F::UINT32: return packAs<std::uint32_t>(dst, v, be);
    case F::FLOAT32: return packAs<float>(dst, v, be);
    default: return packAs<double>(dst, v, be);
  }
}

inline sensor_msgs::PointCloud2 cloudMsg(const CloudSpec& spec, std::int64_t stamp_ns, const std::vector<PointValues>& pts) {
  sensor_msgs::PointCloud2 m;
  m.header.stamp = rosTime(stamp_ns);
  m.header.frame_id = "lidar";
  m.height = spec.height;
  m.width = static_cast<std::uint32_t>(pts.size()) / spec.height;
  for (const auto& f : spec.fields) {
    sensor_msgs::PointField pf;
    pf.name = f.name, pf.offset = f.offset, pf.datatype = f.type, pf.count = 1;
    m.fields.push_back(pf);
  }
  m.is_bigendian = spec.big_endian;
  m.point_step = spec.point_step;
  m.row_step = m.width * spec.point_step;
  m.data.assign(static_cast<std::size_t>(m.row_step) * m.height, 0xAB);
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (const auto& f : spec.fields) pack(&m.data[i * spec.point_step + f.offset], f.type, pts[i].at(f.name), spec.big_endian);
  m.is_dense = false;
  return m;
}

/// Value of a field as the cloud stores it (the test's own view of float rounding).
inline double stored(const CloudSpec& spec, const std::string& name, double v) {
  for (const auto& f : spec.fields)
    if (f.name == name) {
      std::uint8_t buf[8];
      pack(buf, f.type, v, false);
      if (f.type == sensor_msgs::PointField::FLOAT32) {
        float x;
        std::memcpy(&x, buf, 4);
        return x;
      }
      return f.type == sensor_msgs::PointField::FLOAT64 ? v : std::trunc(v);
    }
  return 0;
}


inline std::vector<std::int64_t> writeImuBag(const std::string& path, int n, rosbag::CompressionType compression) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(compression);
  bag.setChunkThreshold(2048);
  std::vector<std::int64_t> stamps;
  for (int i = 0; i < n; ++i) {
    stamps.push_back(kT0 + i * 5'000'000LL);
    bag.write("/imu", rosTime(stamps.back()), imuMsg(stamps.back(), {0.001 * i, 0, 0}, {0, 0, 9.8}));
  }
  return stamps;
}

}  // namespace livo::test

#endif  // LIVO_TEST_ROSBAG
