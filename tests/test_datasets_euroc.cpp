// EuRoC converter: CSV parsing, synthetic EuRoC folders and the shared EuRoC micro set to LCM logs, read back
// and compared with independent parses of the inputs (cv::imread, strtod). Bad inputs must stop with an
// error naming the file and the line.
// livo-test-deps: livo_io livo_common opencv_core opencv_imgcodecs
#include "datasets_test_util.hpp"

#include "livo/common/config.hpp"
#include "livo/datasets/csv.hpp"
#include "livo/datasets/euroc.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/log.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

using namespace livo;
using namespace livo::test;

// ---------------- CSV and EuRoC on synthetic folders ----------------

TEST(Csv, SkipsCommentsBlankLinesAndCrLf) {
  TempDir t;
  writeText(t.path / "a.csv", "# header\r\n1, 2.5 ,x\r\n\r\n  \n3,4,y\n");
  CsvFile csv(t / "a.csv");
  CsvFile::Row row;
  ASSERT_TRUE(csv.next(row));
  EXPECT_EQ(row.line, 2);
  ASSERT_EQ(row.fields.size(), 3u);
  EXPECT_EQ(csv.toInt64(row, 0, "a"), 1);
  EXPECT_EQ(csv.toDouble(row, 1, "b"), 2.5);
  EXPECT_EQ(row.fields[2], "x");
  ASSERT_TRUE(csv.next(row));
  EXPECT_EQ(row.line, 5);
  EXPECT_FALSE(csv.next(row));
  EXPECT_TRUE(contains(errorOf([&] { csv.toDouble(row, 2, "name"); }), "a.csv:5: column 3 (name): not a number"));
}

TEST(Euroc, SyntheticFolderRoundTrip) {
  SyntheticEuroc s;
  const std::string out = s.dir / "out.lcm";
  const ConversionSummary sum = convertEuroc(s.dir.path.string(), out);
  const DecodedLog log = readLog(out);
  ASSERT_EQ(log.images.size(), 3u);
  // Default window: images 1.0 .. 1.1 s, IMU 0.0 .. 2.1 s (1 s margin) -> rows 0..420 at 5 ms.
  ASSERT_EQ(log.imu.size(), 421u);
  EXPECT_EQ(sum.channels.at("LIVO_IMU").events, 421u);
  EXPECT_EQ(sum.channels.at("LIVO_CAMERA").events, 3u);
  EXPECT_EQ(log.imu.front().utime, kEpochNs / 1000);
  EXPECT_EQ(log.imu.back().utime, kEpochNs / 1000 + 2'100'000);
  EXPECT_DOUBLE_EQ(log.imu[7].angular_velocity[0], 0.007);
  EXPECT_DOUBLE_EQ(log.imu[7].linear_acceleration[2], -0.07);
  for (int i = 0; i < 3; ++i) {
    const image_t& m = log.images[static_cast<std::size_t>(i)];
    EXPECT_EQ(m.width, 8);
    EXPECT_EQ(m.height, 6);
    EXPECT_EQ(m.pixel_format, +image_t::GRAY8);  // unary + avoids ODR-using the lcm-gen constant
    EXPECT_EQ(m.data[5 * 8 + 7], 10 * i + 47);
  }
  EXPECT_TRUE(log.utime_matches_log_time);
  EXPECT_TRUE(std::is_sorted(log.log_times.begin(), log.log_times.end()));
  // Equal times: the IMU sample at the image time (row 200, 1.0 s) is written just before the image.
  const auto first_cam = std::find(log.channels.begin(), log.channels.end(), "LIVO_CAMERA") - log.channels.begin();
  ASSERT_GT(first_cam, 0);
  EXPECT_EQ(log.channels[static_cast<std::size_t>(first_cam - 1)], "LIVO_IMU");
  EXPECT_EQ(log.log_times[static_cast<std::size_t>(first_cam - 1)], log.images[0].utime);
  EXPECT_EQ(sum.file_bytes, fs::file_size(out));
}

TEST(Euroc, WindowRelativeAndAbsolute) {
  const Utime first = 1'403'715'273'262'143, last = first + 4'700'000;
  EurocOptions opt;
  EurocWindow w = eurocWindow(first, last, opt);
  EXPECT_EQ(w.image_begin, first);
  EXPECT_EQ(w.image_end, last);
  EXPECT_EQ(w.imu_begin, first - 1'000'000);
  EXPECT_EQ(w.imu_end, last + 1'000'000);
  opt.start_s = 1.0;
  opt.end_s = 2.5;
  opt.imu_margin_s = 0.25;
  w = eurocWindow(first, last, opt);
  EXPECT_EQ(w.image_begin, first + 1'000'000);
  EXPECT_EQ(w.image_end, first + 2'500'000);
  EXPECT_EQ(w.imu_begin, first + 750'000);
  opt.start_s = 1403715274.0;  // absolute sensor time
  opt.end_s.reset();
  w = eurocWindow(first, last, opt);
  EXPECT_EQ(w.image_begin, 1'403'715'274'000'000);
  opt.start_s = 3.0;
  opt.end_s = 1.0;
  EXPECT_TRUE(contains(errorOf([&] { eurocWindow(first, last, opt); }), "is before start"));
}

TEST(Euroc, MalformedImuRowNamesFileAndLine) {
  SyntheticEuroc s;
  s.setImuLine(17, "1403715000080000000,0.1,0.2,0.3,0.4");
  const std::string out = s.dir / "out.lcm";
  const std::string err = errorOf([&] { convertEuroc(s.dir.path.string(), out); });
  EXPECT_TRUE(contains(err, "mav0/imu0/data.csv:17: expected 7 columns, got 5")) << err;
  EXPECT_FALSE(fs::exists(out)) << "a failed conversion must not leave a log";
}

TEST(Euroc, NonNumericAndNonMonotonicRows) {
  SyntheticEuroc s;
  s.setImuLine(9, "1403715000040000000,0.1,abc,0.3,0.4,0.5,0.6");
  std::string err = errorOf([&] { convertEuroc(s.dir.path.string(), s.dir / "o.lcm"); });
  EXPECT_TRUE(contains(err, "mav0/imu0/data.csv:9: column 3 (w_y): not a number: 'abc'")) << err;

  SyntheticEuroc m;
  m.setImuLine(30, "1403715000100000000,0,0,0,0,0,0");  // earlier than line 29 (0.14 s)
  err = errorOf([&] { convertEuroc(m.dir.path.string(), m.dir / "o.lcm"); });
  EXPECT_TRUE(contains(err, "mav0/imu0/data.csv:30: timestamps not increasing (line 30")) << err;

  SyntheticEuroc c;
  c.cam_csv = "#t,f\n1403715001000000000,a.png\n1403715001000000000,b.png\n";
  c.writeAll();
  err = errorOf([&] { readEurocImageCsv(c.dir / "mav0/cam0/data.csv", c.dir / "mav0/cam0/data"); });
  EXPECT_TRUE(contains(err, "a.png: missing image (listed in ")) << err;
  EXPECT_TRUE(contains(err, "mav0/cam0/data.csv:2)")) << err;
}

TEST(Euroc, MissingFilesAndKeys) {
  TempDir t;
  EXPECT_TRUE(contains(errorOf([&] { convertEuroc(t / "nope", t / "o.lcm"); }), "nope: no such directory"));
  fs::create_directories(t.path / "mav0" / "cam0");
  EXPECT_TRUE(contains(errorOf([&] { convertEuroc(t.path.string(), t / "o.lcm"); }), "mav0/imu0: missing sensor folder"));

  SyntheticEuroc s;
  fs::remove(s.dir.path / "mav0" / "imu0" / "data.csv");
  std::string err = errorOf([&] { convertEuroc(s.dir.path.string(), s.dir / "o.lcm"); });
  EXPECT_TRUE(contains(err, "mav0/imu0/data.csv: cannot open")) << err;

  SyntheticEuroc k;
  std::string yaml = kCamYaml;
  yaml.replace(yaml.find("intrinsics"), 10, "intrinsix");
  writeText(k.dir.path / "mav0" / "cam0" / "sensor.yaml", yaml);
  err = errorOf([&] { convertEuroc(k.dir.path.string(), k.dir / "o.lcm"); });
  EXPECT_TRUE(contains(err, "cam0/sensor.yaml")) << err;
  EXPECT_TRUE(contains(err, "intrinsics")) << err;

  SyntheticEuroc r;  // image size differs from sensor.yaml
  yaml = kCamYaml;
  yaml.replace(yaml.find("[8, 6]"), 6, "[9, 6]");
  writeText(r.dir.path / "mav0" / "cam0" / "sensor.yaml", yaml);
  err = errorOf([&] { convertEuroc(r.dir.path.string(), r.dir / "o.lcm"); });
  EXPECT_TRUE(contains(err, ".png: image is 8x6 but sensor.yaml resolution is 9x6")) << err;
  EXPECT_FALSE(fs::exists(r.dir.path / "o.lcm"));
}

TEST(Euroc, RigYamlIsAValidConfig) {
  SyntheticEuroc s;
  const EurocCalibration calib = readEurocCalibration((s.dir.path / "mav0").string());
  const std::string text = eurocRigYaml(calib, "synthetic");
  ConfigFile file = ConfigFile::parse(text, "rig.yaml");
  const ConfigNode root = file.root();
  EXPECT_FALSE(root.has("lidar"));
  const ConfigNode imu = root.section("imu");
  double gyro = 0, walk = 0;
  imu.require("gyro_noise", gyro).require("accel_bias_walk", walk);
  EXPECT_DOUBLE_EQ(gyro, 1.6968e-04);
  EXPECT_DOUBLE_EQ(walk, 3.0e-3);
  const ConfigNode cam = root.section("camera");
  int width = 0;
  double fy = 0;
  std::string model;
  std::vector<double> dist;
  Eigen::Isometry3d T;
  cam.require("width", width).require("fy", fy).require("model", model).require("distortion", dist);
  cam.require("T_imu_camera", T);
  EXPECT_EQ(width, 8);
  EXPECT_DOUBLE_EQ(fy, 101.0);
  EXPECT_EQ(model, "pinhole");
  EXPECT_EQ(dist, (std::vector<double>{-0.1, 0.01, 0.001, 0.0001}));
  // T_BS of the camera (the IMU's is identity): a 90 degree turn about z and a translation.
  Eigen::Matrix3d R;
  R << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_LT((T.rotation() - R).norm(), 1e-9);
  EXPECT_LT((T.translation() - Eigen::Vector3d(0.1, 0.2, 0.3)).norm(), 1e-12);
}

// ---------------- EuRoC micro set (shared data) ----------------

TEST(EurocMicro, ConvertAndReadBack) {
  if (!fs::exists(kEuroc / "mav0")) LIVO_SKIP() << "shared data absent: " << kEuroc;
  TempDir t;
  const std::string out = t / "euroc.lcm";
  const ConversionSummary sum = convertEuroc(kEuroc.string(), out);
  const DecodedLog log = readLog(out);

  // Images: 95, 752x480 GRAY8, pixels identical to cv::imread of the PNG listed at the same row.
  std::vector<std::pair<std::int64_t, std::string>> rows;
  {
    std::ifstream f(kEuroc / "mav0/cam0/data.csv");
    std::string line;
    while (std::getline(f, line)) {
      if (line.empty() || line[0] == '#') continue;
      const auto comma = line.find(',');
      std::string name = line.substr(comma + 1);
      if (!name.empty() && name.back() == '\r') name.pop_back();
      rows.emplace_back(std::stoll(line.substr(0, comma)), name);
    }
  }
  ASSERT_EQ(rows.size(), 95u);
  ASSERT_EQ(log.images.size(), 95u);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const image_t& m = log.images[i];
    EXPECT_EQ(m.utime, (rows[i].first + 500) / 1000);
    ASSERT_EQ(m.width, 752);
    ASSERT_EQ(m.height, 480);
    ASSERT_EQ(m.pixel_format, +image_t::GRAY8);  // unary + avoids ODR-using the lcm-gen constant
    const cv::Mat ref = cv::imread((kEuroc / "mav0/cam0/data" / rows[i].second).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(ref.type(), CV_8UC1);
    ASSERT_TRUE(ref.isContinuous());
    ASSERT_EQ(m.data.size(), ref.total());
    EXPECT_EQ(std::memcmp(m.data.data(), ref.data, ref.total()), 0) << rows[i].second;
  }

  // IMU: exactly the csv rows inside [first image - 1 s, last image + 1 s], values parsed with strtod.
  const Utime begin = log.images.front().utime - 1'000'000, end = log.images.back().utime + 1'000'000;
  std::vector<std::vector<double>> expected;
  std::vector<Utime> expected_t;
  {
    std::ifstream f(kEuroc / "mav0/imu0/data.csv");
    std::string line;
    while (std::getline(f, line)) {
      if (line.empty() || line[0] == '#') continue;
      const char* p = line.c_str();
      char* e = nullptr;
      const long long ns = std::strtoll(p, &e, 10);
      const Utime us = (ns + 500) / 1000;
      if (us < begin || us > end) continue;
      std::vector<double> v;
      for (int k = 0; k < 6; ++k) {
        p = e + 1;  // skip the comma
        v.push_back(std::strtod(p, &e));
      }
      expected.push_back(v);
      expected_t.push_back(us);
    }
  }
  ASSERT_EQ(log.imu.size(), expected.size());
  EXPECT_GT(expected.size(), 1000u);
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(log.imu[i].utime, expected_t[i]);
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(log.imu[i].angular_velocity[k], expected[i][static_cast<std::size_t>(k)]);
      ASSERT_EQ(log.imu[i].linear_acceleration[k], expected[i][static_cast<std::size_t>(3 + k)]);
    }
  }
  EXPECT_TRUE(log.utime_matches_log_time);
  EXPECT_TRUE(std::is_sorted(log.log_times.begin(), log.log_times.end()));
  EXPECT_EQ(sum.events, log.log_times.size());
}

TEST(EurocMicro, RigFromSensorYaml) {
  if (!fs::exists(kEuroc / "mav0")) LIVO_SKIP() << "shared data absent: " << kEuroc;
  const EurocCalibration c = readEurocCalibration((kEuroc / "mav0").string());
  EXPECT_EQ(c.camera.width, 752);
  EXPECT_EQ(c.camera.height, 480);
  EXPECT_DOUBLE_EQ(c.camera.fx, 458.654);
  EXPECT_DOUBLE_EQ(c.camera.distortion[0], -0.28340811);
  EXPECT_DOUBLE_EQ(c.imu.gyro_noise, 1.6968e-04);
  // The rig's quaternion reproduces sensor.yaml's T_BS rotation (stored with ~12 digits).
  ConfigFile file = ConfigFile::parse(eurocRigYaml(c, kEuroc.string()), "rig.yaml");
  Eigen::Isometry3d T;
  file.root().section("camera").require("T_imu_camera", T);
  Eigen::Matrix3d R_bs;
  R_bs << 0.0148655429818, -0.999880929698, 0.00414029679422, 0.999557249008, 0.0149672133247, 0.025715529948,
      -0.0257744366974, 0.00375618835797, 0.999660727178;
  EXPECT_LT((T.rotation() - R_bs).norm(), 1e-6);
  EXPECT_LT((T.translation() - Eigen::Vector3d(-0.0216401454975, -0.064676986768, 0.00981073058949)).norm(), 1e-12);
}
