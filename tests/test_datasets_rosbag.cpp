// ROS 1 bag import: small bags written here with librosbag-storage (sensor_msgs types serialized by ROS's
// own generated code, Livox CustomMsg and odd types by hand), converted, read back from the LCM log and
// compared value by value with what was written. Errors: missing topic, wrong or unknown type, truncated
// bag, corrupt chunk (events before it kept), every truncation of every message.
// livo-test-deps: livo_io livo_rosbag_storage opencv_core opencv_imgcodecs
// livo-test-bins: livo-convert
#include "livo/datasets/rosbag.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/log.hpp"

#include <gtest/gtest.h>

#include <filesystem>

using namespace livo;

#if !defined(LIVO_HAVE_ROSBAG) || !__has_include(<sensor_msgs/Imu.h>)

// Without librosbag-storage-dev (or without libsensor-msgs-dev, which the bag writers here need).
TEST(Rosbag, BuiltWithoutBagSupportSaysSo) {
  if (!rosbagSupported()) {
    try {
      convertRosbag("x.bag", "x.lcm");
      ADD_FAILURE() << "no error";
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find("no ROS bag support"), std::string::npos) << e.what();
    }
  }
  GTEST_SKIP() << "built without librosbag-storage-dev or libsensor-msgs-dev: bag tests skipped";
}

#else

#include <opencv2/imgcodecs.hpp>
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

namespace {

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

constexpr std::int64_t kT0 = 1'650'000'000'000'000'000;  // ns, a 2022 Unix time

ros::Time rosTime(std::int64_t ns) {
  return ros::Time(static_cast<std::uint32_t>(ns / 1'000'000'000), static_cast<std::uint32_t>(ns % 1'000'000'000));
}
/// Independent oracles of the documented rounding rules.
Utime roundUs(std::int64_t ns) { return static_cast<Utime>(std::llround(static_cast<long double>(ns) / 1000)); }
Utime floorUs(std::int64_t ns) { return static_cast<Utime>(std::floor(static_cast<long double>(ns) / 1000)); }

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

template <class F>
std::string errorOf(F&& f) {
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

RawMsg livoxMsg(const std::string& datatype, std::int64_t stamp_ns, const std::vector<LivoxPoint>& pts) {
  Bytes w;
  w.header(stamp_ns).put<std::uint64_t>(static_cast<std::uint64_t>(stamp_ns)).put<std::uint32_t>(pts.size());
  w.put<std::uint8_t>(1).put<std::uint8_t>(0).put<std::uint8_t>(0).put<std::uint8_t>(0);
  w.put<std::uint32_t>(pts.size());
  for (const auto& p : pts)
    w.put(p.offset_ns).put(p.x).put(p.y).put(p.z).put(p.reflectivity).put(p.tag).put(p.line);
  return RawMsg{datatype, rosLayoutMd5(RosType::LivoxCustomMsg), "# livox\n", w.b};
}

sensor_msgs::Imu imuMsg(std::int64_t stamp_ns, const Eigen::Vector3d& gyro, const Eigen::Vector3d& acc) {
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

ReadBack readLog(const std::string& path) {
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

RosbagOptions only(const std::string& lidar, const std::string& imu, const std::string& image) {
  RosbagOptions o;
  o.lidar_topic = lidar, o.imu_topic = imu, o.image_topic = image;
  return o;
}

}  // namespace

namespace {

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
void packAs(std::uint8_t* dst, double v, bool big_endian) {
  const T t = static_cast<T>(v);
  std::memcpy(dst, &t, sizeof(T));
  if (big_endian) std::reverse(dst, dst + sizeof(T));
}

void pack(std::uint8_t* dst, std::uint8_t type, double v, bool be) {
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

sensor_msgs::PointCloud2 cloudMsg(const CloudSpec& spec, std::int64_t stamp_ns, const std::vector<PointValues>& pts) {
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
double stored(const CloudSpec& spec, const std::string& name, double v) {
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

}  // namespace

TEST(Rosbag, SupportIsBuiltIn) { EXPECT_TRUE(rosbagSupported()); }

TEST(Rosbag, LayoutMd5sMatchTheRosHeaders) {
  EXPECT_STREQ(rosLayoutMd5(RosType::Imu), ros::message_traits::MD5Sum<sensor_msgs::Imu>::value());
  EXPECT_STREQ(rosLayoutMd5(RosType::PointCloud2), ros::message_traits::MD5Sum<sensor_msgs::PointCloud2>::value());
  EXPECT_STREQ(rosLayoutMd5(RosType::Image), ros::message_traits::MD5Sum<sensor_msgs::Image>::value());
  EXPECT_STREQ(rosLayoutMd5(RosType::CompressedImage),
               ros::message_traits::MD5Sum<sensor_msgs::CompressedImage>::value());
  EXPECT_EQ(rosTypeOf("livox_ros_driver2/CustomMsg"), RosType::LivoxCustomMsg);
  EXPECT_EQ(rosTypeOf("std_msgs/String"), RosType::Unknown);
}

TEST(Rosbag, ImuValuesAndStampsWithEveryChunkCompression) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  const std::int64_t sub_us[5] = {0, 499, 500, 501, 999};  // ns parts that exercise the rounding
  for (auto compression : {rosbag::compression::Uncompressed, rosbag::compression::BZ2, rosbag::compression::LZ4}) {
    SCOPED_TRACE(static_cast<int>(compression));
    TempDir t;
    std::vector<std::int64_t> stamps;
    std::vector<Eigen::Vector3d> gyro, acc;
    {
      rosbag::Bag bag(t / "imu.bag", rosbag::bagmode::Write);
      bag.setCompression(compression);
      bag.setChunkThreshold(4096);
      for (int i = 0; i < 60; ++i) {
        stamps.push_back(kT0 + i * 5'000'000LL + sub_us[i % 5]);
        gyro.emplace_back(noise(rng), noise(rng), noise(rng));
        acc.push_back(Eigen::Vector3d(0.1, -0.2, 9.8) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
        bag.write("/imu", rosTime(stamps.back() + 2'000'000), imuMsg(stamps.back(), gyro.back(), acc.back()));
      }
    }
    const RosbagSummary s = convertRosbag(t / "imu.bag", t / "imu.lcm");
    EXPECT_TRUE(s.error.empty()) << s.error;
    EXPECT_EQ(s.topics.imu, "/imu");
    EXPECT_TRUE(contains(s.accel_note, "m/s^2")) << s.accel_note;
    const ReadBack r = readLog(t / "imu.lcm");
    ASSERT_EQ(r.imu.size(), stamps.size());
    for (std::size_t i = 0; i < stamps.size(); ++i) {
      EXPECT_EQ(r.imu[i].utime, roundUs(stamps[i])) << i;
      EXPECT_EQ(r.imu[i].gyro, gyro[i]) << i;  // float64 all the way: exact
      EXPECT_EQ(r.imu[i].accel, acc[i]) << i;
    }
  }
}

TEST(Rosbag, ImuAccelerationInGIsDetectedAndConverted) {
  TempDir t;
  {
    rosbag::Bag bag(t / "g.bag", rosbag::bagmode::Write);
    for (int i = 0; i < 30; ++i) {
      const std::int64_t st = kT0 + i * 5'000'000LL;
      bag.write("/livox/imu", rosTime(st), imuMsg(st, Eigen::Vector3d(0.01 * i, 0, 0), Eigen::Vector3d(0.02, -0.01, 1.0 + 0.001 * i)));
    }
  }
  RosbagSummary s = convertRosbag(t / "g.bag", t / "g.lcm");
  EXPECT_DOUBLE_EQ(s.accel_scale, 9.80665);
  EXPECT_TRUE(contains(s.accel_note, "in g detected")) << s.accel_note;
  ReadBack r = readLog(t / "g.lcm");
  ASSERT_EQ(r.imu.size(), 30u);
  for (int i = 0; i < 30; ++i) {
    EXPECT_DOUBLE_EQ(r.imu[i].accel.z(), (1.0 + 0.001 * i) * 9.80665);
    EXPECT_DOUBLE_EQ(r.imu[i].accel.x(), 0.02 * 9.80665);
    EXPECT_DOUBLE_EQ(r.imu[i].gyro.x(), 0.01 * i);  // gyro untouched
  }
  RosbagOptions keep;
  keep.imu_accel_unit = AccelUnit::MetresPerSecond2;
  s = convertRosbag(t / "g.bag", t / "g2.lcm", keep);
  EXPECT_DOUBLE_EQ(readLog(t / "g2.lcm").imu[5].accel.z(), 1.005);
  // Neither ~1 g nor ~9.8 m/s^2: kept, with a warning.
  std::string note;
  EXPECT_EQ(detectAccelScale({3.0, 3.1, 2.9}, RosbagOptions{}, note), 1.0);
  EXPECT_TRUE(contains(note, "WARNING")) << note;
}

TEST(Rosbag, PointCloud2LayoutsOfTheCommonDrivers) {
  using F = sensor_msgs::PointField;
  // Per layout: fields, and how the test expects the absolute time (ns) of a point to come out.
  struct Case {
    CloudSpec spec;
    std::function<PointValues(int i, int n, std::int64_t header_ns)> point;
    std::function<std::int64_t(const PointValues& v, std::int64_t header_ns)> abs_ns;  // -1: no times
    std::string ring_field, intensity_field;
  };
  auto xyz = [](int i) {
    return PointValues{{"x", 1.0 + 0.37 * i}, {"y", -2.0 + 0.11 * i}, {"z", 0.5 - 0.013 * i}};
  };
  std::vector<Case> cases;
  // Velodyne: time float32 s relative to the header, negative (header at the scan end), ring uint16.
  cases.push_back({{"velodyne", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                     {"ring", F::UINT16, 16}, {"time", F::FLOAT32, 18}}, 22},
                   [&](int i, int n, std::int64_t) { auto v = xyz(i); v["intensity"] = 3.5 * i; v["ring"] = i % 16; v["time"] = -0.1 + 0.1 * i / n; return v; },
                   [](const PointValues& v, std::int64_t h) { return h + std::llround(static_cast<double>(static_cast<float>(v.at("time"))) * 1e9); },
                   "ring", "intensity"});
  // Ouster: organized (4 rows), t uint32 ns, intensity float32, reflectivity uint16, ring uint8; both endians.
  for (bool be : {false, true})
    cases.push_back({{be ? "ouster_big_endian" : "ouster", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8},
                       {"intensity", F::FLOAT32, 16}, {"t", F::UINT32, 20}, {"reflectivity", F::UINT16, 24}, {"ring", F::UINT8, 26},
                       {"range", F::UINT32, 32}}, 48, 4, be},
                     [&](int i, int n, std::int64_t) { auto v = xyz(i); v["intensity"] = 100 + i; v["t"] = (i * 7919) % 99'000'000 + 13;
                       v["reflectivity"] = 7; v["ring"] = i / (n / 4); v["range"] = 1000; return v; },
                     [](const PointValues& v, std::int64_t h) { return h + static_cast<std::int64_t>(v.at("t")); }, "ring", "intensity"});
  // Hesai (Hilti 2022): timestamp float64 absolute s; header stamp at the scan end is not used.
  cases.push_back({{"hesai", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                     {"timestamp", F::FLOAT64, 16}, {"ring", F::UINT16, 24}}, 32},
                   [&](int i, int n, std::int64_t h) { auto v = xyz(i); v["intensity"] = i; v["ring"] = 31 - i % 32;
                     v["timestamp"] = static_cast<double>(h - 100'000'000) * 1e-9 + 0.1 * i / n; return v; },
                   [](const PointValues& v, std::int64_t) { return std::llround(v.at("timestamp") * 1e9); }, "ring", "intensity"});
  // livox_ros_driver2 PointCloud2: timestamp float64 absolute ns, line uint8.
  cases.push_back({{"livox2_pointcloud", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                     {"tag", F::UINT8, 16}, {"line", F::UINT8, 17}, {"timestamp", F::FLOAT64, 18}}, 26},
                   [&](int i, int, std::int64_t h) { auto v = xyz(i); v["intensity"] = 200 - i; v["tag"] = 0x10; v["line"] = i % 6;
                     v["timestamp"] = static_cast<double>(h + 1000 * i + 250); return v; },
                   [](const PointValues& v, std::int64_t) { return std::llround(v.at("timestamp")); }, "line", "intensity"});
  // Livox-style offset_time uint32 ns; reflectivity uint8 instead of intensity; unaligned fields.
  cases.push_back({{"offset_time_unaligned", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8},
                     {"reflectivity", F::UINT8, 12}, {"offset_time", F::UINT32, 13}, {"line", F::UINT8, 17}}, 18},
                   [&](int i, int n, std::int64_t) { auto v = xyz(i); v["reflectivity"] = 3 * i; v["line"] = i % 4;
                     v["offset_time"] = 100'000'000.0 * (n - i) / n; return v; },
                   [](const PointValues& v, std::int64_t h) { return h + static_cast<std::int64_t>(v.at("offset_time")); },
                   "line", "reflectivity"});
  // float64 coordinates, no time field: offsets 0, utime = header.
  cases.push_back({{"xyz64_untimed", {{"x", F::FLOAT64, 0}, {"y", F::FLOAT64, 8}, {"z", F::FLOAT64, 16}}, 24},
                   [&](int i, int, std::int64_t) { return xyz(i); }, nullptr, "", ""});

  for (const Case& c : cases) {
    SCOPED_TRACE(c.spec.name);
    TempDir t;
    const int n = 40;
    std::vector<std::vector<PointValues>> sent;
    std::vector<std::int64_t> headers;
    {
      rosbag::Bag bag(t / "c.bag", rosbag::bagmode::Write);
      for (int k = 0; k < 2; ++k) {
        headers.push_back(kT0 + k * 100'000'000LL + 777);
        std::vector<PointValues> pts;
        for (int i = 0; i < n; ++i) pts.push_back(c.point(i, n, headers.back()));
        if (c.spec.name == "velodyne") pts[3]["x"] = std::nan("");  // dropped
        bag.write("/points", rosTime(headers.back() + 100'000'000), cloudMsg(c.spec, headers.back(), pts));
        sent.push_back(pts);
      }
    }
    const RosbagSummary s = convertRosbag(t / "c.bag", t / "c.lcm");
    ASSERT_TRUE(s.error.empty()) << s.error;
    const ReadBack r = readLog(t / "c.lcm");
    ASSERT_EQ(r.scans.size(), 2u);
    for (int k = 0; k < 2; ++k) {
      std::vector<PointValues> expect;
      for (const auto& p : sent[k])
        if (std::isfinite(p.at("x"))) expect.push_back(p);
      const LidarScan& scan = r.scans[k];
      EXPECT_EQ(scan.sensor, "generic");
      ASSERT_EQ(scan.points.size(), expect.size());
      std::vector<std::int64_t> abs;
      for (const auto& p : expect) abs.push_back(c.abs_ns ? c.abs_ns(p, headers[k]) : headers[k]);
      const std::int64_t t_min = *std::min_element(abs.begin(), abs.end());
      EXPECT_EQ(scan.utime, c.abs_ns ? floorUs(t_min) : roundUs(headers[k]));
      for (std::size_t i = 0; i < expect.size(); ++i) {
        const LidarPoint& q = scan.points[i];
        EXPECT_EQ(q.p_lidar.x(), static_cast<float>(stored(c.spec, "x", expect[i].at("x")))) << i;
        EXPECT_EQ(q.p_lidar.y(), static_cast<float>(stored(c.spec, "y", expect[i].at("y")))) << i;
        EXPECT_EQ(q.p_lidar.z(), static_cast<float>(stored(c.spec, "z", expect[i].at("z")))) << i;
        const double off = c.abs_ns ? static_cast<double>(abs[i] - scan.utime * 1000) * 1e-9 : 0.0;
        EXPECT_NEAR(q.time_offset_s, off, 2e-8) << i;
        EXPECT_GE(q.time_offset_s, 0.f) << i;
        EXPECT_EQ(q.intensity, c.intensity_field.empty() ? 0.f : static_cast<float>(stored(c.spec, c.intensity_field, expect[i].at(c.intensity_field)))) << i;
        EXPECT_EQ(q.ring, c.ring_field.empty() ? -1 : static_cast<int>(expect[i].at(c.ring_field))) << i;
      }
    }
    if (c.spec.name == "velodyne") {
      EXPECT_TRUE(contains(s.describe(), "2 points with non-finite coordinates dropped")) << s.describe();
    }
    if (!c.abs_ns) {
      EXPECT_TRUE(contains(s.describe(), "without a per-point time field")) << s.describe();
    }
  }
}

TEST(Rosbag, LivoxCustomMsgOfBothDrivers) {
  for (const std::string datatype : {"livox_ros_driver/CustomMsg", "livox_ros_driver2/CustomMsg"}) {
    SCOPED_TRACE(datatype);
    TempDir t;
    std::vector<LivoxPoint> pts;
    for (int i = 0; i < 50; ++i)
      pts.push_back({static_cast<std::uint32_t>(1'000 + (i * 37) % 50 * 2'000'000LL), 0.5f * i, -0.25f * i, 0.125f + i,
                     static_cast<std::uint8_t>(5 * i), 0x10, static_cast<std::uint8_t>(i % 6)});
    pts[7].y = std::numeric_limits<float>::infinity();  // dropped
    const std::int64_t header = kT0 + 123'456'789;
    {
      rosbag::Bag bag(t / "l.bag", rosbag::bagmode::Write);
      bag.write("/livox/lidar", rosTime(header + 100'000'000), livoxMsg(datatype, header, pts));
    }
    const RosbagSummary s = convertRosbag(t / "l.bag", t / "l.lcm");
    ASSERT_TRUE(s.error.empty()) << s.error;
    const ReadBack r = readLog(t / "l.lcm");
    ASSERT_EQ(r.scans.size(), 1u);
    const LidarScan& scan = r.scans[0];
    EXPECT_EQ(scan.sensor, "avia");
    EXPECT_EQ(scan.utime, floorUs(header + 1'000));  // earliest offset_time is 1000 ns
    pts.erase(pts.begin() + 7);
    ASSERT_EQ(scan.points.size(), pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const LidarPoint& q = scan.points[i];
      EXPECT_EQ(q.p_lidar, Eigen::Vector3f(pts[i].x, pts[i].y, pts[i].z)) << i;
      EXPECT_EQ(q.intensity, pts[i].reflectivity) << i;
      EXPECT_EQ(q.ring, pts[i].line) << i;
      EXPECT_NEAR(q.time_offset_s, static_cast<double>(header + pts[i].offset_ns - scan.utime * 1000) * 1e-9, 2e-8) << i;
    }
  }
}

TEST(Rosbag, RawImageEncodings) {
  struct Case {
    std::string encoding;
    int bytes_per_pixel;
    bool big_endian;
    int mono16_bits;
    PixelFormat expect_format;
  };
  const std::vector<Case> cases = {
      {"mono8", 1, false, 0, PixelFormat::Gray8},     {"rgb8", 3, false, 0, PixelFormat::Rgb8},
      {"bgr8", 3, false, 0, PixelFormat::Bgr8},       {"rgba8", 4, false, 0, PixelFormat::Rgb8},
      {"mono16", 2, false, 0, PixelFormat::Gray16},   {"16UC1", 2, true, 0, PixelFormat::Gray16},
      {"mono16", 2, false, 12, PixelFormat::Gray8}};
  const int w = 5, h = 3;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.encoding + (c.big_endian ? " big-endian" : "") + " bits " + std::to_string(c.mono16_bits));
    TempDir t;
    sensor_msgs::Image m;
    const std::int64_t stamp = kT0 + 33'333'500;
    m.header.stamp = rosTime(stamp);
    m.height = h, m.width = w, m.encoding = c.encoding, m.is_bigendian = c.big_endian;
    m.step = w * c.bytes_per_pixel + 3;  // padded rows
    m.data.assign(static_cast<std::size_t>(m.step) * h, 0xEE);
    std::vector<int> values;  // pixel channel values, row-major
    for (int r = 0; r < h; ++r)
      for (int x = 0; x < w * (c.bytes_per_pixel == 2 ? 1 : c.bytes_per_pixel); ++x) {
        const int v = c.bytes_per_pixel == 2 ? (r * 1999 + x * 977 + 16) % 5000 : (r * 50 + x * 7) % 256;
        values.push_back(v);
        std::uint8_t* p = &m.data[r * m.step + (c.bytes_per_pixel == 2 ? 2 * x : x)];
        if (c.bytes_per_pixel == 2) {
          p[c.big_endian ? 0 : 1] = static_cast<std::uint8_t>(v >> 8);
          p[c.big_endian ? 1 : 0] = static_cast<std::uint8_t>(v & 0xFF);
        } else {
          *p = static_cast<std::uint8_t>(v);
        }
      }
    {
      rosbag::Bag bag(t / "i.bag", rosbag::bagmode::Write);
      bag.write("/cam/image_raw", rosTime(stamp), m);
    }
    RosbagOptions opt;
    opt.mono16_bits = c.mono16_bits;
    const RosbagSummary s = convertRosbag(t / "i.bag", t / "i.lcm", opt);
    ASSERT_TRUE(s.error.empty()) << s.error;
    const ReadBack r = readLog(t / "i.lcm");
    ASSERT_EQ(r.images.size(), 1u);
    const Image& img = r.images[0];
    EXPECT_EQ(img.utime, roundUs(stamp));
    EXPECT_EQ(img.format, c.expect_format);
    EXPECT_EQ(img.width, w);
    EXPECT_EQ(img.height, h);
    const int out_bpp = bytesPerPixel(c.expect_format);
    for (int row = 0; row < h; ++row)
      for (int x = 0; x < w; ++x) {
        const std::uint8_t* px = &img.data[static_cast<std::size_t>(row) * img.row_stride + x * out_bpp];
        if (c.encoding == "rgba8") {
          for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(px[ch], values[(row * w + x) * 4 + ch]);
        } else if (c.bytes_per_pixel == 2 && c.mono16_bits == 0) {
          EXPECT_EQ(px[0] | (px[1] << 8), values[row * w + x]);  // GRAY16 little-endian
        } else if (c.bytes_per_pixel == 2) {
          EXPECT_EQ(px[0], std::min(255, values[row * w + x] >> 4));
        } else {
          for (int ch = 0; ch < out_bpp; ++ch) EXPECT_EQ(px[ch], values[(row * w + x) * out_bpp + ch]);
        }
      }
  }
}

TEST(Rosbag, CompressedImagesPassThroughAndABadOneStops) {
  TempDir t;
  cv::Mat gray(30, 40, CV_8UC1), color(9, 17, CV_8UC3);
  cv::randu(gray, 0, 255);
  cv::randu(color, 0, 255);
  std::vector<std::uint8_t> jpg, png;
  ASSERT_TRUE(cv::imencode(".jpg", gray, jpg));
  ASSERT_TRUE(cv::imencode(".png", color, png));
  const std::vector<std::pair<std::string, std::vector<std::uint8_t>>> streams = {
      {"jpeg", jpg}, {"bgr8; png compressed bgr8", png}, {"jpeg", {1, 2, 3, 4, 5, 6, 7, 8}}, {"jpeg", jpg}};
  {
    rosbag::Bag bag(t / "c.bag", rosbag::bagmode::Write);
    for (std::size_t i = 0; i < streams.size(); ++i) {
      sensor_msgs::CompressedImage m;
      m.header.stamp = rosTime(kT0 + static_cast<std::int64_t>(i) * 100'000'000LL);
      m.format = streams[i].first;
      m.data = streams[i].second;
      bag.write("/cam/image/compressed", rosTime(kT0 + static_cast<std::int64_t>(i) * 100'000'000LL), m);
    }
  }
  RosbagSummary s = convertRosbag(t / "c.bag", t / "c.lcm");
  EXPECT_TRUE(contains(s.error, "message 2")) << s.error;
  EXPECT_TRUE(contains(s.error, "neither a JPEG nor a PNG")) << s.error;
  ReadBack r = readLog(t / "c.lcm");  // the two images before the bad one are kept
  ASSERT_EQ(r.images.size(), 2u);
  EXPECT_EQ(r.images[0].format, PixelFormat::Jpeg);
  EXPECT_EQ(r.images[0].width, 40);
  EXPECT_EQ(r.images[0].height, 30);
  EXPECT_EQ(r.images[0].data, jpg);
  EXPECT_EQ(r.images[1].format, PixelFormat::Png);
  EXPECT_EQ(r.images[1].width, 17);
  EXPECT_EQ(r.images[1].height, 9);
  EXPECT_EQ(r.images[1].data, png);
  EXPECT_EQ(r.images[1].utime, roundUs(kT0 + 100'000'000));

  RosbagOptions skip;
  skip.skip_bad_messages = true;
  s = convertRosbag(t / "c.bag", t / "c2.lcm", skip);
  EXPECT_TRUE(s.error.empty());
  EXPECT_TRUE(contains(s.describe(), "1 malformed messages skipped")) << s.describe();
  EXPECT_EQ(readLog(t / "c2.lcm").images.size(), 3u);
}

TEST(Rosbag, EventsOfAllTopicsComeOutInTimeOrder) {
  TempDir t;
  {
    rosbag::Bag bag(t / "a.bag", rosbag::bagmode::Write);
    using F = sensor_msgs::PointField;
    const CloudSpec ouster{"o", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"t", F::UINT32, 12}}, 16};
    // Written in record-time order: IMU 1 ms late, scans 100 ms late (recorded at their end), images 20 ms.
    std::vector<std::pair<std::int64_t, std::function<void(ros::Time)>>> writes;
    for (int i = 0; i < 200; ++i) {
      const std::int64_t st = kT0 + i * 5'000'000LL;
      writes.push_back({st + 1'000'000, [&bag, st](ros::Time rt) { bag.write("/imu", rt, imuMsg(st, {0, 0, 0}, {0, 0, 9.8})); }});
    }
    for (int k = 0; k < 10; ++k) {
      const std::int64_t st = kT0 + k * 100'000'000LL + 3'000'000;
      writes.push_back({st + 100'000'000, [&bag, st, ouster](ros::Time rt) {
                          std::vector<PointValues> pts;
                          for (int i = 0; i < 10; ++i) pts.push_back({{"x", 1}, {"y", i}, {"z", 0}, {"t", i * 9'000'000}});
                          bag.write("/os_cloud_node/points", rt, cloudMsg(ouster, st, pts));
                        }});
      const std::int64_t ct = kT0 + k * 100'000'000LL + 50'000'000;
      writes.push_back({ct + 20'000'000, [&bag, ct](ros::Time rt) {
                          sensor_msgs::Image m;
                          m.header.stamp = rosTime(ct);
                          m.height = 2, m.width = 2, m.encoding = "mono8", m.step = 2, m.data = {1, 2, 3, 4};
                          bag.write("/cam0/image_raw", rt, m);
                        }});
    }
    // One IMU sample stamped 0.8 s in the past: beyond the reorder window, dropped.
    writes.push_back({kT0 + 1'000'000'000, [&bag](ros::Time rt) { bag.write("/imu", rt, imuMsg(kT0 + 200'000'000, {0, 0, 0}, {0, 0, 9.8})); }});
    // One IMU sample with a glitched stamp 1000 s ahead: kept, written last, nothing else lost.
    writes.push_back({kT0 + 500'000'000, [&bag](ros::Time rt) { bag.write("/imu", rt, imuMsg(kT0 + 1000'000'000'000LL, {0, 0, 0}, {0, 0, 9.8})); }});
    std::stable_sort(writes.begin(), writes.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [rt, w] : writes) w(rosTime(rt));
  }
  RosbagOptions opt;
  opt.reorder_window_s = 0.5;
  const RosbagSummary s = convertRosbag(t / "a.bag", t / "a.lcm", opt);
  ASSERT_TRUE(s.error.empty()) << s.error;
  EXPECT_EQ(s.topics.lidar, "/os_cloud_node/points");
  EXPECT_EQ(s.topics.image, "/cam0/image_raw");
  const ReadBack r = readLog(t / "a.lcm");
  ASSERT_EQ(r.imu.size(), 201u);
  EXPECT_EQ(r.imu.back().utime, (kT0 + 1000'000'000'000LL) / 1000);
  EXPECT_EQ(r.scans.size(), 10u);
  EXPECT_EQ(r.images.size(), 10u);
  EXPECT_TRUE(std::is_sorted(r.times.begin(), r.times.end()));
  EXPECT_TRUE(contains(s.describe(), "1 LIVO_IMU events arrived later than the reorder window")) << s.describe();
  for (int k = 0; k < 10; ++k) EXPECT_EQ(r.scans[k].utime, (kT0 + k * 100'000'000LL + 3'000'000) / 1000);
}

TEST(Rosbag, TopicSelectionErrorsNameTheTopics) {
  TempDir t;
  {
    rosbag::Bag bag(t / "s.bag", rosbag::bagmode::Write);
    bag.write("/imu_a", rosTime(kT0), imuMsg(kT0, {0, 0, 0}, {0, 0, 9.8}));
    bag.write("/imu_b", rosTime(kT0), imuMsg(kT0, {0, 0, 0}, {0, 0, 9.8}));
    bag.write("/chatter", rosTime(kT0), RawMsg{"std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1", "string data\n", Bytes().str("hi").b});
    bag.write("/bad_md5", rosTime(kT0), RawMsg{"sensor_msgs/Imu", "0123456789abcdef0123456789abcdef", "# old\n", {}});
  }
  const std::string bag = t / "s.bag", out = t / "s.lcm";
  std::string e = errorOf([&] { convertRosbag(bag, out); });
  EXPECT_TRUE(contains(e, "several IMU topics; choose one with --imu-topic")) << e;
  EXPECT_TRUE(contains(e, "/imu_a (sensor_msgs/Imu, 1 messages)")) << e;
  e = errorOf([&] { convertRosbag(bag, out, only("", "/nope", "")); });
  EXPECT_TRUE(contains(e, "no topic /nope (--imu-topic)")) << e;
  EXPECT_TRUE(contains(e, "/chatter (std_msgs/String")) << e;
  e = errorOf([&] { convertRosbag(bag, out, only("/chatter", "/imu_a", "")); });
  EXPECT_TRUE(contains(e, "topic /chatter has type std_msgs/String, which is not a LiDAR type")) << e;
  e = errorOf([&] { convertRosbag(bag, out, only("", "/bad_md5", "")); });
  EXPECT_TRUE(contains(e, "definition MD5 0123456789abcdef0123456789abcdef is not the layout")) << e;
  e = errorOf([&] { convertRosbag(bag, out, only("none", "none", "none")); });
  EXPECT_TRUE(contains(e, "no LiDAR, IMU or camera topic to convert")) << e;
  EXPECT_FALSE(fs::exists(out));  // nothing written for errors found before the first message
  const RosbagSummary s = convertRosbag(bag, out, only("", "/imu_b", ""));
  EXPECT_EQ(s.conversion.events, 1u);
}

/// Offsets and sizes of the data of every chunk record (op 0x05) of a bag file (format 2.0 records:
/// header length, header fields "name=value" each with a length, data length, data).
std::vector<std::pair<std::size_t, std::size_t>> chunkData(const std::vector<char>& f) {
  std::vector<std::pair<std::size_t, std::size_t>> chunks;
  std::size_t pos = 13;  // "#ROSBAG V2.0\n"
  auto u32 = [&](std::size_t at) {
    std::uint32_t v;
    std::memcpy(&v, &f[at], 4);
    return v;
  };
  while (pos + 4 <= f.size()) {
    const std::uint32_t hlen = u32(pos);
    const std::string header(&f[pos + 4], hlen);
    const std::size_t data_at = pos + 4 + hlen + 4;
    const std::uint32_t dlen = u32(pos + 4 + hlen);
    if (header.find(std::string("op=\x05", 4)) != std::string::npos) chunks.emplace_back(data_at, dlen);
    pos = data_at + dlen;
  }
  return chunks;
}

std::vector<char> readFile(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}
void writeFile(const std::string& p, const std::vector<char>& d) {
  std::ofstream(p, std::ios::binary).write(d.data(), static_cast<std::streamsize>(d.size()));
}

std::vector<std::int64_t> writeImuBag(const std::string& path, int n, rosbag::CompressionType compression) {
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

TEST(Rosbag, TruncatedBagIsAClearError) {
  TempDir t;
  writeImuBag(t / "full.bag", 300, rosbag::compression::BZ2);
  std::vector<char> bytes = readFile(t / "full.bag");
  bytes.resize(bytes.size() * 6 / 10);
  writeFile(t / "cut.bag", bytes);
  const std::string e = errorOf([&] { convertRosbag(t / "cut.bag", t / "cut.lcm"); });
  EXPECT_TRUE(contains(e, "cut.bag")) << e;
  EXPECT_TRUE(contains(e, "truncated")) << e;
  EXPECT_FALSE(fs::exists(t / "cut.lcm"));
  EXPECT_TRUE(contains(errorOf([&] { convertRosbag(t / "missing.bag", t / "m.lcm"); }), "missing.bag: no such file"));
}

TEST(Rosbag, CorruptChunkStopsAndKeepsTheEventsBeforeIt) {
  TempDir t;
  const std::vector<std::int64_t> stamps = writeImuBag(t / "ok.bag", 400, rosbag::compression::BZ2);
  std::vector<char> bytes = readFile(t / "ok.bag");
  const auto chunks = chunkData(bytes);
  ASSERT_GT(chunks.size(), 10u);
  const auto [at, len] = chunks[chunks.size() / 2];
  for (std::size_t i = at + len / 3; i < at + len / 3 + 16; ++i) bytes[i] = static_cast<char>(bytes[i] ^ 0x5A);
  writeFile(t / "bad.bag", bytes);
  const RosbagSummary s = convertRosbag(t / "bad.bag", t / "bad.lcm");
  EXPECT_TRUE(contains(s.error, "bad.bag: cannot read message")) << s.error;
  EXPECT_TRUE(contains(s.error, "topic /imu")) << s.error;
  EXPECT_TRUE(contains(s.error, "corrupt")) << s.error;
  EXPECT_TRUE(contains(s.describe(), "STOPPED EARLY")) << s.describe();
  const ReadBack r = readLog(t / "bad.lcm");
  EXPECT_GT(r.imu.size(), 100u);  // about half of the chunks come before the corrupt one
  EXPECT_LT(r.imu.size(), stamps.size());
  EXPECT_EQ(r.imu.size(), s.conversion.events);
  for (std::size_t i = 0; i < r.imu.size(); ++i) {
    EXPECT_EQ(r.imu[i].utime, roundUs(stamps[i]));
    EXPECT_EQ(r.imu[i].gyro.x(), 0.001 * static_cast<double>(i));
  }
}

/// Serialized bytes of a ROS message (the generated serializer).
template <class M>
std::vector<std::uint8_t> serialize(const M& m) {
  std::vector<std::uint8_t> buf(ros::serialization::serializationLength(m));
  ros::serialization::OStream s(buf.data(), static_cast<std::uint32_t>(buf.size()));
  ros::serialization::serialize(s, m);
  return buf;
}

TEST(RosMsgs, EveryTruncationAndOversizedLengthIsAnError) {
  using F = sensor_msgs::PointField;
  const CloudSpec spec{"c", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"t", F::UINT32, 12}}, 16};
  std::vector<PointValues> pts(6, PointValues{{"x", 1}, {"y", 2}, {"z", 3}, {"t", 5}});
  sensor_msgs::Image img;
  img.height = 2, img.width = 3, img.encoding = "rgb8", img.step = 9, img.data.assign(18, 7);
  sensor_msgs::CompressedImage jpg;
  jpg.format = "jpeg";
  cv::Mat m(8, 8, CV_8UC1, cv::Scalar(90));
  cv::imencode(".jpg", m, jpg.data);
  const RosDecodeOptions opt;
  const std::vector<std::pair<std::string, std::vector<std::uint8_t>>> msgs = {
      {"imu", serialize(imuMsg(kT0, {1, 2, 3}, {4, 5, 6}))},
      {"cloud", serialize(cloudMsg(spec, kT0, pts))},
      {"livox", livoxMsg("livox_ros_driver/CustomMsg", kT0, {{1, 1, 2, 3, 4, 5, 6}, {2, 1, 2, 3, 4, 5, 6}}).bytes},
      {"image", serialize(img)},
      {"compressed", serialize(jpg)}};
  auto decodeAny = [&](const std::string& kind, const std::uint8_t* d, std::size_t n) {
    if (kind == "imu") decodeRosImu(d, n);
    else if (kind == "cloud") decodeRosPointCloud2(d, n, opt);
    else if (kind == "livox") decodeLivoxCustomMsg(d, n, opt);
    else if (kind == "image") decodeRosImage(d, n, opt);
    else decodeRosCompressedImage(d, n, opt);
  };
  for (const auto& [kind, bytes] : msgs) {
    SCOPED_TRACE(kind);
    EXPECT_NO_THROW(decodeAny(kind, bytes.data(), bytes.size()));
    for (std::size_t len = 0; len < bytes.size(); ++len) {
      std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(len));
      EXPECT_THROW(decodeAny(kind, cut.data(), cut.size()), DatasetError) << len;
    }
    std::vector<std::uint8_t> longer = bytes;
    longer.push_back(0);
    EXPECT_TRUE(contains(errorOf([&] { decodeAny(kind, longer.data(), longer.size()); }), "unexpected bytes")) << kind;
  }
  // A declared data length far beyond the message: refused before any allocation.
  std::vector<std::uint8_t> cloud = msgs[1].second;
  const std::size_t data_len_at = cloud.size() - 1 - 6 * 16 - 4;
  const std::uint32_t huge = 0xFFFFFFF0u;
  std::memcpy(&cloud[data_len_at], &huge, 4);
  const std::string e = errorOf([&] { decodeRosPointCloud2(cloud.data(), cloud.size(), opt); });
  EXPECT_TRUE(contains(e, "sensor_msgs/PointCloud2.data: declares 4294967280 bytes")) << e;
}

TEST(Rosbag, LivoConvertBinary) {
  const std::string bin = std::string(LIVO_BINARY_DIR) + "/bin/livo-convert";
  if (!fs::exists(bin)) GTEST_SKIP() << "binary not built: " << bin;
  TempDir t;
  writeImuBag(t / "b.bag", 20, rosbag::compression::LZ4);
  const std::string out = t / "b.lcm", txt = t / "out.txt", err = t / "err.txt";
  int rc = std::system((bin + " rosbag " + (t / "b.bag") + " --out " + out + " --imu-topic /imu --quiet > " + txt + " 2> " + err).c_str());
  EXPECT_EQ(rc, 0);
  std::ifstream f(txt);
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(text, "LIVO_IMU")) << text;
  EXPECT_EQ(readLog(out).imu.size(), 20u);
  rc = std::system((bin + " rosbag " + (t / "b.bag") + " --out " + (t / "x.lcm") + " --lidar-topic /nope 2> " + err).c_str());
  EXPECT_NE(rc, 0);
  std::ifstream e(err);
  const std::string etext((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(etext, "no topic /nope (--lidar-topic)")) << etext;
}

// Opt-in figure: conversion speed on a ~100 MB bag of Velodyne-style clouds (random points) and 200 Hz IMU,
// per chunk compression. Run with --gtest_also_run_disabled_tests --gtest_filter=*ConversionSpeed*.
TEST(Rosbag, DISABLED_ConversionSpeed) {
  using F = sensor_msgs::PointField;
  const CloudSpec velo{"v", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                             {"ring", F::UINT16, 16}, {"time", F::FLOAT32, 18}}, 22};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-50, 50);
  std::vector<PointValues> pts;
  for (int i = 0; i < 22'000; ++i)
    pts.push_back({{"x", u(rng)}, {"y", u(rng)}, {"z", u(rng) / 10}, {"intensity", i % 255}, {"ring", i % 32}, {"time", 0.1 * i / 22'000}});
  sensor_msgs::PointCloud2 m = cloudMsg(velo, kT0, pts);
  for (auto compression : {rosbag::compression::Uncompressed, rosbag::compression::LZ4, rosbag::compression::BZ2}) {
    TempDir t;
    {
      rosbag::Bag bag(t / "big.bag", rosbag::bagmode::Write);
      bag.setCompression(compression);
      for (std::int64_t k = 0; k < 200; ++k) {
        const std::int64_t st = kT0 + k * 100'000'000LL;
        for (std::int64_t i = 0; i < 20; ++i)
          bag.write("/imu", rosTime(st + i * 5'000'000LL), imuMsg(st + i * 5'000'000LL, {0, 0, 0}, {0, 0, 9.8}));
        m.header.stamp = rosTime(st);
        bag.write("/velodyne_points", rosTime(st + 99'900'000LL), m);  // no record-time ties across chunks
      }
    }
    const double mb = static_cast<double>(fs::file_size(t / "big.bag")) / (1 << 20);
    const auto t0 = std::chrono::steady_clock::now();
    const RosbagSummary s = convertRosbag(t / "big.bag", t / "big.lcm");
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_TRUE(s.error.empty());
    std::printf("compression %d: %.1f MiB bag (%llu messages, %.1f MiB of messages) converted in %.2f s: %.0f MiB/s of bag\n",
                static_cast<int>(compression), mb, static_cast<unsigned long long>(s.messages_read),
                static_cast<double>(s.conversion.file_bytes) / (1 << 20), sec, mb / sec);
  }
}

#endif  // LIVO_HAVE_ROSBAG and sensor_msgs
