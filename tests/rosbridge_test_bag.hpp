// The bag of tests/test_rosbridge.cpp: every message type and PointCloud2 layout `livo-convert rosbag`
// reads, plus what both must skip (an empty cloud) or reject (a truncated PointCloud2), on the topics of
// three bridges:
//   A: /imu (sensor_msgs/Imu, in g), /points (PointCloud2, one layout per message), /cam/image_raw (Image,
//      one encoding per message);
//   B: /livox/lidar (livox_ros_driver/CustomMsg), /cam/compressed (CompressedImage, JPEG and PNG);
//   C: /livox2/lidar (livox_ros_driver2/CustomMsg).
// Every topic's stamps increase in record order, so the converter's time-ordered log and the bridge's
// arrival order agree per channel.
#pragma once

#include "datasets_rosbag_test_util.hpp"

#if LIVO_TEST_ROSBAG

#include <opencv2/imgcodecs.hpp>

namespace livo::test {

struct BridgeBag {
  int imu = 0, points = 0, points_bad = 0, points_empty = 0, images = 0, livox = 0, livox2 = 0, compressed = 0;
};

inline std::vector<PointValues> cloudPoints(const CloudSpec& spec, int n, std::int64_t header_ns) {
  std::vector<PointValues> pts;
  for (int i = 0; i < n; ++i) {
    PointValues v{{"x", 1.0 + 0.37 * i}, {"y", -2.0 + 0.11 * i}, {"z", 0.5 - 0.013 * i}};
    for (const auto& f : spec.fields) {
      if (f.name == "intensity" || f.name == "reflectivity") v[f.name] = 3 * i + 1;
      if (f.name == "ring" || f.name == "line") v[f.name] = i % 16;
      if (f.name == "time") v[f.name] = -0.05 + 0.1 * i / n;                            // s, relative
      if (f.name == "t" || f.name == "offset_time") v[f.name] = 1'000'000.0 * i + 13;   // ns, relative
      if (f.name == "timestamp")  // absolute: s (float64) for Hesai, ns for livox_ros_driver2
        v[f.name] = spec.name == "livox2" ? static_cast<double>(header_ns + 1000 * i + 250)
                                          : static_cast<double>(header_ns) * 1e-9 + 0.001 * i;
      if (f.name == "tag") v[f.name] = 0x10;
    }
    pts.push_back(v);
  }
  if (n > 3) pts[3]["x"] = std::nan("");  // dropped by the decoder (counted)
  return pts;
}

inline std::vector<CloudSpec> bridgeCloudLayouts() {
  using F = sensor_msgs::PointField;
  return {
      {"velodyne", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                    {"ring", F::UINT16, 16}, {"time", F::FLOAT32, 18}}, 22},
      {"ouster", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 16},
                  {"t", F::UINT32, 20}, {"reflectivity", F::UINT16, 24}, {"ring", F::UINT8, 26}}, 48, 2},
      {"ouster_big_endian", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 16},
                             {"t", F::UINT32, 20}, {"ring", F::UINT8, 26}}, 48, 1, true},
      {"hesai", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                 {"timestamp", F::FLOAT64, 16}, {"ring", F::UINT16, 24}}, 32},
      {"livox2", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                  {"tag", F::UINT8, 16}, {"line", F::UINT8, 17}, {"timestamp", F::FLOAT64, 18}}, 26},
      {"offset_time", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"reflectivity", F::UINT8, 12},
                       {"offset_time", F::UINT32, 13}, {"line", F::UINT8, 17}}, 18},
      {"xyz64_untimed", {{"x", F::FLOAT64, 0}, {"y", F::FLOAT64, 8}, {"z", F::FLOAT64, 16}}, 24},
  };
}

inline sensor_msgs::Image rawImage(const std::string& encoding, int bytes_per_pixel, bool big_endian,
                                   std::int64_t stamp_ns, int seed) {
  sensor_msgs::Image m;
  m.header.stamp = rosTime(stamp_ns);
  m.header.frame_id = "cam";
  m.height = 6, m.width = 8, m.encoding = encoding, m.is_bigendian = big_endian;
  m.step = m.width * bytes_per_pixel + 2;  // padded rows
  m.data.resize(static_cast<std::size_t>(m.step) * m.height);
  for (std::size_t i = 0; i < m.data.size(); ++i) m.data[i] = static_cast<std::uint8_t>((i * 37 + seed * 11) % 251);
  return m;
}

inline sensor_msgs::CompressedImage compressedImage(const std::string& ext, std::int64_t stamp_ns) {
  cv::Mat img(8, 16, CV_8UC1);
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) img.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(r * 20 + c * 5);
  sensor_msgs::CompressedImage m;
  m.header.stamp = rosTime(stamp_ns);
  m.format = ext == ".png" ? "mono8; png compressed " : "mono8; jpeg compressed ";
  cv::imencode(ext, img, m.data);
  return m;
}

/// Writes the bag; returns what it holds.
inline BridgeBag writeBridgeBag(const std::string& path) {
  BridgeBag n;
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  // IMU: 400 samples at 200 Hz, acceleration in g (the bridge holds the first 200 for the unit decision).
  for (int i = 0; i < 400; ++i, ++n.imu) {
    const std::int64_t st = kT0 + i * 5'000'000LL + 499 * (i % 3);
    bag.write("/imu", rosTime(st), imuMsg(st, {0.01 * i, -0.02, 0.003}, {0.01, -0.02, 1.0 + 0.001 * std::sin(i)}));
  }
  // PointCloud2: one layout per message, then an empty cloud (skipped) and a truncated one (rejected).
  std::int64_t st = kT0 + 7'000'000;
  for (const CloudSpec& spec : bridgeCloudLayouts()) {
    bag.write("/points", rosTime(st + 100'000'000), cloudMsg(spec, st, cloudPoints(spec, 24, st)));
    st += 100'000'000;
    ++n.points;
  }
  bag.write("/points", rosTime(st + 100'000'000), cloudMsg(bridgeCloudLayouts()[0], st, {}));
  ++n.points_empty;
  st += 100'000'000;
  {
    const auto m = cloudMsg(bridgeCloudLayouts()[0], st, cloudPoints(bridgeCloudLayouts()[0], 24, st));
    std::vector<std::uint8_t> bytes(ros::serialization::serializationLength(m));
    ros::serialization::OStream os(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
    ros::serialization::serialize(os, m);
    bytes.resize(bytes.size() - 100);  // cut inside the point data
    bag.write("/points", rosTime(st + 100'000'000),
              RawMsg{"sensor_msgs/PointCloud2", rosLayoutMd5(RosType::PointCloud2), "# cut\n", bytes});
    ++n.points_bad;
    st += 100'000'000;
  }
  bag.write("/points", rosTime(st + 100'000'000), cloudMsg(bridgeCloudLayouts()[3], st, cloudPoints(bridgeCloudLayouts()[3], 24, st)));
  ++n.points;
  // Image encodings.
  struct Enc {
    const char* name;
    int bpp;
    bool be;
  };
  int k = 0;
  for (const Enc& e : {Enc{"mono8", 1, false}, Enc{"rgb8", 3, false}, Enc{"bgr8", 3, false}, Enc{"bgra8", 4, false},
                       Enc{"mono16", 2, false}, Enc{"16UC1", 2, true}, Enc{"8UC1", 1, false}}) {
    const std::int64_t it = kT0 + 20'000'000 + k * 50'000'000LL;
    bag.write("/cam/image_raw", rosTime(it + 5'000'000), rawImage(e.name, e.bpp, e.be, it, k));
    ++k, ++n.images;
  }
  // Livox CustomMsg of both drivers (a non-finite point in the second scan of each).
  for (const char* type : {"livox_ros_driver/CustomMsg", "livox_ros_driver2/CustomMsg"}) {
    const bool v2 = std::string(type).find('2') != std::string::npos;
    for (int s = 0; s < 3; ++s) {
      const std::int64_t ls = kT0 + 11'000'000 + s * 100'000'000LL;
      std::vector<LivoxPoint> pts;
      for (int i = 0; i < 30; ++i)
        pts.push_back({static_cast<std::uint32_t>(i * 3'000'000 + 17), 2.0f + 0.1f * i, -0.5f * i, 0.25f,
                       static_cast<std::uint8_t>(i * 5), 0x10, static_cast<std::uint8_t>(i % 6)});
      if (s == 1) pts[4].y = std::numeric_limits<float>::infinity();
      bag.write(v2 ? "/livox2/lidar" : "/livox/lidar", rosTime(ls + 100'000'000), livoxMsg(type, ls, pts));
      ++(v2 ? n.livox2 : n.livox);
    }
  }
  // Compressed images: JPEG and PNG (passed through).
  bag.write("/cam/compressed", rosTime(kT0 + 30'000'000), compressedImage(".jpg", kT0 + 25'000'000));
  bag.write("/cam/compressed", rosTime(kT0 + 130'000'000), compressedImage(".png", kT0 + 125'000'000));
  n.compressed = 2;
  return n;
}

}  // namespace livo::test

#endif  // LIVO_TEST_ROSBAG
