// ROS 1 bag import of damaged input: a truncated bag, a corrupt chunk (events before it kept), and every
// truncation or oversized length of every decoded message type is a clear error.
// livo-test-deps: livo_io livo_rosbag_storage opencv_core opencv_imgcodecs
#include "datasets_rosbag_test_util.hpp"

#include <gtest/gtest.h>

using namespace livo;

#if LIVO_TEST_ROSBAG

#include <opencv2/imgcodecs.hpp>

using namespace livo::test;

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

#endif  // LIVO_TEST_ROSBAG
