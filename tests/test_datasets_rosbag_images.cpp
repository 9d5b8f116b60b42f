// ROS 1 bag import of camera messages: raw image encodings compared pixel by pixel, compressed images
// passed through, and a bad compressed image stops the conversion.
// livo-test-deps: livo_io livo_rosbag_storage opencv_core opencv_imgcodecs
#include "datasets_rosbag_test_util.hpp"

#include <gtest/gtest.h>

using namespace livo;

#if LIVO_TEST_ROSBAG

#include <opencv2/imgcodecs.hpp>

using namespace livo::test;

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

#endif  // LIVO_TEST_ROSBAG
