// Dataset converters: EuRoC folders and KITTI-style .bin scans to LCM logs, read back and compared with
// independent parses of the inputs (cv::imread, strtod, raw float32 bytes). Bad inputs must stop with an
// error naming the file and the line (text) or the byte size (binary).
// livo-test-deps: livo_io livo_common opencv_core opencv_imgcodecs
#include "livo/common/config.hpp"
#include "livo/datasets/csv.hpp"
#include "livo/datasets/euroc.hpp"
#include "livo/datasets/kitti.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/log.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

namespace fs = std::filesystem;
using namespace livo;

namespace {

const fs::path kData = fs::path(LIVO_SHARED_DATA);
const fs::path kEuroc = kData / "euroc_v1_01_micro";
const fs::path kScans = kData / "kitti_newer_college_scans";

/// A fresh temporary folder removed at the end of the test.
struct TempDir {
  fs::path path;
  TempDir() {
    static int counter = 0;
    path = fs::temp_directory_path() /
           ("livo_test_datasets_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

void writeFloats(const fs::path& p, const std::vector<float>& v) {
  fs::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary);
  f.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(float)));
}

std::vector<float> readFloatsOracle(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  std::vector<float> v(bytes.size() / 4);
  std::memcpy(v.data(), bytes.data(), v.size() * 4);
  return v;
}

/// Runs `fn` and returns the DatasetError message (empty when nothing was thrown).
template <class Fn>
std::string errorOf(Fn&& fn) {
  try {
    fn();
  } catch (const DatasetError& e) {
    return e.what();
  }
  return "";
}

/// All events of a log, decoded by channel.
struct DecodedLog {
  std::vector<imu_t> imu;
  std::vector<image_t> images;
  std::vector<lidar_scan_t> scans;
  std::vector<Utime> log_times;
  std::vector<std::string> channels;
  bool utime_matches_log_time = true;
};

DecodedLog readLog(const std::string& path) {
  DecodedLog out;
  LogReader reader(path);
  LogEvent ev;
  while (reader.next(ev)) {
    out.log_times.push_back(ev.timestamp);
    out.channels.push_back(ev.channel);
    Utime utime = 0;
    if (ev.channel == "LIVO_IMU") {
      imu_t m;
      EXPECT_TRUE(decode(ev.data.data(), ev.data.size(), m)) << ev.eventnum;
      out.imu.push_back(m);
      utime = m.utime;
    } else if (ev.channel == "LIVO_CAMERA") {
      image_t m;
      EXPECT_TRUE(decode(ev.data.data(), ev.data.size(), m)) << ev.eventnum;
      out.images.push_back(m);
      utime = m.utime;
    } else if (ev.channel == "LIVO_LIDAR") {
      lidar_scan_t m;
      EXPECT_TRUE(decode(ev.data.data(), ev.data.size(), m)) << ev.eventnum;
      out.scans.push_back(m);
      utime = m.utime;
    } else {
      ADD_FAILURE() << "unexpected channel " << ev.channel;
    }
    if (utime != ev.timestamp) out.utime_matches_log_time = false;
  }
  return out;
}

// ---- a tiny synthetic EuRoC folder (always available, no shared data needed) ----
const char* kCamYaml = R"(%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [0.0, -1.0, 0.0, 0.1,
         1.0, 0.0, 0.0, 0.2,
         0.0, 0.0, 1.0, 0.3,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [8, 6]
camera_model: pinhole
intrinsics: [100.0, 101.0, 4.0, 3.0] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.1, 0.01, 0.001, 0.0001]
)";
const char* kImuYaml = R"(%YAML:1.0
sensor_type: imu
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
rate_hz: 200
gyroscope_noise_density: 1.6968e-04
gyroscope_random_walk: 1.9393e-05
accelerometer_noise_density: 2.0000e-3
accelerometer_random_walk: 3.0000e-3
)";

/// 3 images at 1.0, 1.05, 1.1 s and IMU at 200 Hz from 0 to 3 s after an EuRoC-like epoch (ns).
constexpr std::int64_t kEpochNs = 1'403'715'000'000'000'000;
struct SyntheticEuroc {
  TempDir dir;
  std::string imu_csv, cam_csv;
  SyntheticEuroc() {
    const fs::path mav = dir.path / "mav0";
    writeText(mav / "cam0" / "sensor.yaml", kCamYaml);
    writeText(mav / "imu0" / "sensor.yaml", kImuYaml);
    std::ostringstream cam;
    cam << "#timestamp [ns],filename\r\n";  // EuRoC files may have CRLF endings
    for (int i = 0; i < 3; ++i) {
      const std::int64_t ns = kEpochNs + 1'000'000'000 + std::int64_t{i} * 50'000'000;
      cam << ns << "," << ns << ".png\r\n";
      cv::Mat img(6, 8, CV_8UC1);
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 8; ++c) img.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(10 * i + 8 * r + c);
      fs::create_directories(mav / "cam0" / "data");
      cv::imwrite((mav / "cam0" / "data" / (std::to_string(ns) + ".png")).string(), img);
    }
    cam_csv = cam.str();
    std::ostringstream imu;
    imu << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y,w_RS_S_z,a_RS_S_x [m s^-2],a_RS_S_y,a_RS_S_z\n";
    for (std::int64_t i = 0; i <= 600; ++i)
      imu << kEpochNs + i * 5'000'000 << "," << 0.001 * i << ",-0.5,0.25," << 9.81 << ",0.1," << -0.01 * i << "\n";
    imu_csv = imu.str();
    writeAll();
  }
  void writeAll() const {
    writeText(dir.path / "mav0" / "cam0" / "data.csv", cam_csv);
    writeText(dir.path / "mav0" / "imu0" / "data.csv", imu_csv);
  }
  /// Replaces line `line` (1-based) of the IMU csv.
  void setImuLine(int line, const std::string& text) {
    std::istringstream in(imu_csv);
    std::ostringstream out;
    std::string l;
    for (int n = 1; std::getline(in, l); ++n) out << (n == line ? text : l) << "\n";
    imu_csv = out.str();
    writeAll();
  }
};

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

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
  if (!fs::exists(kEuroc / "mav0")) GTEST_SKIP() << "shared data absent: " << kEuroc;
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
  if (!fs::exists(kEuroc / "mav0")) GTEST_SKIP() << "shared data absent: " << kEuroc;
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

// ---------------- KITTI-style scans ----------------

TEST(Kitti, Kitti00AutoDetectsXyzAndKeepsValues) {
  if (!fs::exists(kScans / "kitti_00")) GTEST_SKIP() << "shared data absent: " << kScans;
  // Note: despite the data README ("x,y,z,intensity"), these files hold x,y,z records: 000001.bin is
  // 1495260 bytes, a multiple of 12 but not of 16, and auto-detection must pick xyz for the folder.
  TempDir t;
  KittiOptions opt;
  const ConversionSummary sum = convertKitti((kScans / "kitti_00").string(), t / "k.lcm", opt);
  const DecodedLog log = readLog(t / "k.lcm");
  ASSERT_EQ(log.scans.size(), 2u);
  EXPECT_EQ(sum.channels.at("LIVO_LIDAR").events, 2u);
  const char* names[2] = {"000000.bin", "000001.bin"};
  for (int s = 0; s < 2; ++s) {
    const lidar_scan_t& m = log.scans[static_cast<std::size_t>(s)];
    const std::vector<float> raw = readFloatsOracle(kScans / "kitti_00" / names[s]);
    ASSERT_EQ(static_cast<std::size_t>(m.num_points) * 12, fs::file_size(kScans / "kitti_00" / names[s]));
    EXPECT_EQ(m.utime, s * 100'000);
    EXPECT_EQ(m.sensor, "generic");
    for (std::size_t i = 0; i < static_cast<std::size_t>(m.num_points); ++i) {
      ASSERT_EQ(m.x[i], raw[3 * i]);
      ASSERT_EQ(m.y[i], raw[3 * i + 1]);
      ASSERT_EQ(m.z[i], raw[3 * i + 2]);
      ASSERT_EQ(m.time_offset_s[i], 0.f);
      ASSERT_EQ(m.ring[i], -1);
    }
  }
  // A single file of that folder is ambiguous (1496016 bytes is a multiple of 12 and 16).
  const std::string err = errorOf([&] { convertKitti((kScans / "kitti_00/000000.bin").string(), t / "a.lcm"); });
  EXPECT_TRUE(contains(err, "000000.bin: ambiguous record size")) << err;
  EXPECT_TRUE(contains(err, "--fields")) << err;
  EXPECT_FALSE(fs::exists(t / "a.lcm"));
}

TEST(Kitti, Newer06PairsTimesFiles) {
  if (!fs::exists(kScans / "newer_06")) GTEST_SKIP() << "shared data absent: " << kScans;
  TempDir t;
  KittiOptions opt;
  // Two series (raw_*, deskewed_*) in one folder: the converter must ask which one.
  EXPECT_TRUE(contains(errorOf([&] { convertKitti((kScans / "newer_06").string(), t / "n.lcm", opt); }),
                       "several scan series (deskewed_*, raw_*)"));
  opt.prefix = "raw_";
  opt.start_time_s = 5.0;
  opt.rate_hz = 20.0;
  convertKitti((kScans / "newer_06").string(), t / "n.lcm", opt);
  const DecodedLog log = readLog(t / "n.lcm");
  ASSERT_EQ(log.scans.size(), 3u);
  for (int s = 0; s < 3; ++s) {
    const std::string id = "0" + std::to_string(s);
    const std::vector<float> raw = readFloatsOracle(kScans / "newer_06" / ("raw_" + id + ".bin"));
    const std::vector<float> times = readFloatsOracle(kScans / "newer_06" / ("times_" + id + ".bin"));
    const lidar_scan_t& m = log.scans[static_cast<std::size_t>(s)];
    EXPECT_EQ(m.utime, 5'000'000 + s * 50'000);
    ASSERT_EQ(static_cast<std::size_t>(m.num_points), raw.size() / 3);
    ASSERT_EQ(static_cast<std::size_t>(m.num_points), times.size());
    for (std::size_t i = 0; i < times.size(); ++i) {
      ASSERT_EQ(m.x[i], raw[3 * i]);
      ASSERT_EQ(m.z[i], raw[3 * i + 2]);
      ASSERT_EQ(m.time_offset_s[i], times[i]);
    }
    EXPECT_GT(*std::max_element(m.time_offset_s.begin(), m.time_offset_s.end()), 0.09f);
  }
}

TEST(Kitti, DumpLayoutWithSubfolders) {
  if (!fs::exists(kScans / "kitti_07_dump")) GTEST_SKIP() << "shared data absent: " << kScans;
  TempDir t;
  KittiOptions opt;
  opt.synth_times = SynthTimes::Azimuth;
  convertKitti((kScans / "kitti_07_dump").string(), t / "d.lcm", opt);
  const DecodedLog log = readLog(t / "d.lcm");
  ASSERT_EQ(log.scans.size(), 5u);
  for (std::size_t s = 0; s < 5; ++s) {
    const fs::path f = kScans / "kitti_07_dump" / ("00000" + std::to_string(s)) / "points.bin";
    EXPECT_EQ(static_cast<std::size_t>(log.scans[s].num_points) * 12, fs::file_size(f));
    for (float dt : log.scans[s].time_offset_s) {
      ASSERT_GE(dt, 0.f);
      ASSERT_LE(dt, 0.1f);
    }
  }
}

TEST(Kitti, AzimuthTimesMatchASimulatedSpin) {
  // Oracle: 4 rings stored ring after ring (KITTI order), each a full turn fired at a constant rate
  // starting at azimuth 30 degrees; spin clockwise (Velodyne) or counter-clockwise.
  for (const double spin : {-1.0, 1.0}) {
    LidarScan scan;
    std::vector<float> truth;
    const double period = 0.1;
    const int per_ring = 900;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> range(2.0, 50.0);
    for (int ring = 0; ring < 4; ++ring)
      for (int k = 0; k < per_ring; ++k) {
        const double t = period * k / per_ring;
        const double az = 30.0 * M_PI / 180.0 + spin * 2.0 * M_PI * t / period;
        const double r = range(rng);
        LidarPoint p;
        p.p_lidar = Eigen::Vector3f(static_cast<float>(r * std::cos(az)), static_cast<float>(r * std::sin(az)),
                                    static_cast<float>(0.1 * ring - 0.2));
        scan.points.push_back(p);
        truth.push_back(static_cast<float>(t));
      }
    scan.points[5].p_lidar.x() = std::nanf("");  // a NaN return gets offset 0
    synthAzimuthTimes(scan, period);
    EXPECT_EQ(scan.points[5].time_offset_s, 0.f);
    double worst = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      if (i == 5) continue;
      double d = std::abs(scan.points[i].time_offset_s - truth[i]);
      d = std::min(d, period - d);  // the very first firing may land at either end of the period
      worst = std::max(worst, d);
    }
    EXPECT_LT(worst, 1e-6) << "spin " << spin;
  }
}

TEST(Kitti, BadInputNamesTheFile) {
  TempDir t;
  writeFloats(t.path / "flat" / "000000.bin", std::vector<float>(12, 1.f));  // 48 bytes: 4 xyz or 3 xyzi
  writeFloats(t.path / "flat" / "000001.bin", std::vector<float>(7, 1.f));   // 28 bytes: neither
  std::string err = errorOf([&] { convertKitti(t / "flat", t / "o.lcm"); });
  EXPECT_TRUE(contains(err, "000001.bin: 28 bytes is neither a multiple of 12")) << err;
  KittiOptions xyzi;
  xyzi.fields = PointFields::Xyzi;
  err = errorOf([&] { convertKitti(t / "flat", t / "o.lcm", xyzi); });
  EXPECT_TRUE(contains(err, "000001.bin: 28 bytes is not a multiple of the record size 16")) << err;
  EXPECT_FALSE(fs::exists(t / "o.lcm"));

  // Ambiguous folder, resolved by an explicit layout.
  fs::remove(t.path / "flat" / "000001.bin");
  err = errorOf([&] { convertKitti(t / "flat", t / "o.lcm"); });
  EXPECT_TRUE(contains(err, "ambiguous record size")) << err;
  convertKitti(t / "flat", t / "o.lcm", xyzi);
  EXPECT_EQ(readLog(t / "o.lcm").scans.at(0).num_points, 3);

  // Times file: count mismatch, bad values, and a missing pair.
  writeFloats(t.path / "ser" / "raw_00.bin", std::vector<float>(9, 1.f));  // 3 xyz points (36 bytes)
  writeFloats(t.path / "ser" / "times_00.bin", {0.f, 0.05f});
  err = errorOf([&] { convertKitti(t / "ser", t / "o2.lcm"); });
  EXPECT_TRUE(contains(err, "raw_00.bin: 36 bytes fits neither 12 nor 16 bytes per point for the 2 times")) << err;
  KittiOptions xyz;
  xyz.fields = PointFields::Xyz;
  err = errorOf([&] { convertKitti(t / "ser", t / "o2.lcm", xyz); });
  EXPECT_TRUE(contains(err, "times_00.bin: 2 times for 3 points")) << err;
  writeFloats(t.path / "ser" / "times_00.bin", {0.f, std::nanf(""), 0.05f});
  err = errorOf([&] { convertKitti(t / "ser", t / "o2.lcm"); });
  EXPECT_TRUE(contains(err, "times_00.bin: time 1 (byte 4) is nan")) << err;
  writeFloats(t.path / "ser" / "times_00.bin", {0.f, 0.02f, 0.05f});
  writeFloats(t.path / "ser" / "raw_01.bin", std::vector<float>(9, 2.f));
  err = errorOf([&] { convertKitti(t / "ser", t / "o2.lcm"); });
  EXPECT_TRUE(contains(err, "raw_01.bin: no time file times_01.bin")) << err;
  writeFloats(t.path / "ser" / "times_01.bin", {0.f, 0.03f, 0.06f});
  convertKitti(t / "ser", t / "o2.lcm");
  const DecodedLog ok = readLog(t / "o2.lcm");
  ASSERT_EQ(ok.scans.size(), 2u);
  EXPECT_EQ(ok.scans[1].time_offset_s[2], 0.06f);

  // Missing folder, empty folder, empty file, dump subfolder without points.bin.
  EXPECT_TRUE(contains(errorOf([&] { convertKitti(t / "absent", t / "o3.lcm"); }), "absent: no such file or directory"));
  fs::create_directories(t.path / "empty");
  EXPECT_TRUE(contains(errorOf([&] { convertKitti(t / "empty", t / "o3.lcm"); }), "empty: no scans"));
  writeFloats(t.path / "zero" / "0.bin", {});
  EXPECT_TRUE(contains(errorOf([&] { convertKitti(t / "zero", t / "o3.lcm"); }), "0.bin: empty file"));
  writeFloats(t.path / "dump" / "000000" / "points.bin", std::vector<float>(3, 1.f));
  fs::create_directories(t.path / "dump" / "000001");
  EXPECT_TRUE(contains(errorOf([&] { convertKitti(t / "dump", t / "o3.lcm"); }), "000001/points.bin: missing file"));
}

// ---------------- the binary, end to end ----------------

TEST(LivoConvert, BinaryEndToEnd) {
  const std::string bin = std::string(LIVO_BINARY_DIR) + "/bin/livo-convert";
  if (!fs::exists(bin)) GTEST_SKIP() << "binary not built: " << bin;
  SyntheticEuroc s;
  const std::string out = s.dir / "e.lcm", rig = s.dir / "rig.yaml", txt = s.dir / "stdout.txt";
  int rc = std::system((bin + " euroc " + s.dir.path.string() + " --out " + out + " --rig " + rig + " --quiet > " +
                        txt + " 2>&1").c_str());
  EXPECT_EQ(rc, 0);
  std::ifstream f(txt);
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(text, "LIVO_CAMERA")) << text;
  EXPECT_TRUE(contains(text, "LIVO_IMU")) << text;
  EXPECT_EQ(readLog(out).images.size(), 3u);
  EXPECT_TRUE(fs::exists(rig));

  // Bad input: non-zero exit and a message naming file and line.
  s.setImuLine(5, "1,2,3");
  const std::string err = s.dir / "stderr.txt";
  const std::string bad_out = s.dir / "bad.lcm";
  rc = std::system((bin + " euroc " + s.dir.path.string() + " --out " + bad_out + " 2> " + err + " > /dev/null").c_str());
  EXPECT_NE(rc, 0);
  std::ifstream e(err);
  const std::string etext((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(etext, "mav0/imu0/data.csv:5: expected 7 columns, got 3")) << etext;
  EXPECT_FALSE(fs::exists(bad_out));

  // Unknown format.
  rc = std::system((bin + " bagfile x.bag --out " + out + " 2> " + err).c_str());
  EXPECT_NE(rc, 0);
  std::ifstream u(err);
  const std::string utext((std::istreambuf_iterator<char>(u)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(utext, "unknown format 'bagfile'")) << utext;
}
