// Readers of the EuRoC / ASL folder files: sensor.yaml calibrations, data.csv tables and the images.
#include "livo/common/config.hpp"
#include "livo/datasets/csv.hpp"
#include "livo/datasets/euroc.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace livo {

namespace {

/// Loads a sensor.yaml. The OpenCV-style "%YAML:1.0" directive is not YAML 1.2: it is turned into a
/// comment (keeping the line numbers) before parsing.
ConfigFile loadSensorYaml(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DatasetError(path + ": cannot open (missing file?)");
  std::ostringstream text;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("%YAML", 0) == 0) line = "#" + line;
    text << line << '\n';
  }
  try {
    return ConfigFile::parse(text.str(), path);
  } catch (const ConfigError& e) {
    throw DatasetError(e.what());
  }
}

/// T_BS: a 4x4 row-major matrix {rows: 4, cols: 4, data: [16 values]} with a rigid rotation block.
Eigen::Isometry3d readTbs(const ConfigNode& root) {
  const ConfigNode tbs = root.requireSection("T_BS");
  std::vector<double> data;
  tbs.require("data", data);
  tbs.check(data.size() == 16, "data", "expected 16 values (4x4 row-major), got " + std::to_string(data.size()));
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = data[static_cast<std::size_t>(4 * r + c)];
  tbs.check(m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9), "data", "last row must be [0, 0, 0, 1]");
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  const double ortho_err = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
  tbs.check(ortho_err < 1e-3 && R.determinant() > 0, "data",
            "rotation block is not a rotation (|R^T R - I| = " + std::to_string(ortho_err) + ")");
  // Re-orthonormalise through the quaternion (the files store ~12 digits).
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  T.translation() = m.topRightCorner<3, 1>();
  return T;
}

}  // namespace

Utime nsToUtime(std::int64_t ns) { return (ns + 500) / 1000; }

EurocCameraCalibration readEurocCameraYaml(const std::string& path) {
  const ConfigFile file = loadSensorYaml(path);
  const ConfigNode root = file.root();
  EurocCameraCalibration c;
  try {
    std::vector<int> resolution;
    root.require("resolution", resolution);
    root.check(resolution.size() == 2 && resolution[0] > 0 && resolution[1] > 0, "resolution",
               "expected [width, height] with positive values");
    c.width = resolution[0];
    c.height = resolution[1];
    std::vector<double> k;
    root.require("intrinsics", k);
    root.check(k.size() == 4 && k[0] > 0 && k[1] > 0, "intrinsics", "expected [fu, fv, cu, cv] with fu, fv > 0");
    c.fx = k[0], c.fy = k[1], c.cx = k[2], c.cy = k[3];
    std::string camera_model = "pinhole";
    root.get("camera_model", camera_model);
    root.check(camera_model == "pinhole", "camera_model", "unsupported model '" + camera_model + "' (pinhole only)");
    std::string dist_model;
    root.require("distortion_model", dist_model);
    root.require("distortion_coefficients", c.distortion);
    if (dist_model == "radial-tangential" || dist_model == "radtan" || dist_model == "plumb_bob") {
      c.model = CameraKind::Pinhole;
      // A trailing k3 = 0 (5-coefficient plumb_bob) carries no information; any other k3 is unsupported.
      if (c.distortion.size() == 5 && c.distortion[4] == 0.0) c.distortion.pop_back();
      root.check(c.distortion.size() == 4, "distortion_coefficients",
                 "radial-tangential needs [k1, k2, p1, p2], got " + std::to_string(c.distortion.size()) + " values");
    } else if (dist_model == "equidistant" || dist_model == "fisheye" || dist_model == "kannala-brandt") {
      c.model = CameraKind::Equidistant;
      root.check(c.distortion.size() == 4, "distortion_coefficients",
                 "equidistant needs [k1, k2, k3, k4], got " + std::to_string(c.distortion.size()) + " values");
    } else {
      root.fail("distortion_model", "unsupported model '" + dist_model + "' (radial-tangential | equidistant)");
    }
    root.get("rate_hz", c.rate_hz);
    c.T_body_camera = readTbs(root);
  } catch (const ConfigError& e) {
    throw DatasetError(e.what());
  }
  return c;
}

EurocImuCalibration readEurocImuYaml(const std::string& path) {
  const ConfigFile file = loadSensorYaml(path);
  const ConfigNode root = file.root();
  EurocImuCalibration c;
  try {
    root.require("rate_hz", c.rate_hz);
    root.require("gyroscope_noise_density", c.gyro_noise);
    root.require("accelerometer_noise_density", c.accel_noise);
    root.require("gyroscope_random_walk", c.gyro_bias_walk);
    root.require("accelerometer_random_walk", c.accel_bias_walk);
    root.check(c.rate_hz > 0, "rate_hz", "must be positive");
    root.check(c.gyro_noise >= 0, "gyroscope_noise_density", "must be non-negative");
    root.check(c.accel_noise >= 0, "accelerometer_noise_density", "must be non-negative");
    root.check(c.gyro_bias_walk >= 0, "gyroscope_random_walk", "must be non-negative");
    root.check(c.accel_bias_walk >= 0, "accelerometer_random_walk", "must be non-negative");
    c.T_body_imu = readTbs(root);
  } catch (const ConfigError& e) {
    throw DatasetError(e.what());
  }
  return c;
}

std::string eurocMavDir(const std::string& dir, const EurocOptions& opt) {
  if (!fs::is_directory(dir)) throw DatasetError(dir + ": no such directory");
  const fs::path mav = fs::path(dir) / "mav0";
  const std::string base = fs::is_directory(mav) ? mav.string() : dir;
  for (const std::string& sensor : {opt.camera, opt.imu})
    if (!fs::is_directory(fs::path(base) / sensor))
      throw DatasetError((fs::path(base) / sensor).string() +
                         ": missing sensor folder (expected an EuRoC/ASL folder with mav0/" + opt.camera +
                         " and mav0/" + opt.imu + ")");
  return base;
}

EurocCalibration readEurocCalibration(const std::string& mav_dir, const EurocOptions& opt) {
  EurocCalibration c;
  c.camera = readEurocCameraYaml((fs::path(mav_dir) / opt.camera / "sensor.yaml").string());
  c.imu = readEurocImuYaml((fs::path(mav_dir) / opt.imu / "sensor.yaml").string());
  return c;
}

std::vector<ImuSample> readEurocImuCsv(const std::string& path) {
  static const char* kNames[7] = {"timestamp_ns", "w_x", "w_y", "w_z", "a_x", "a_y", "a_z"};
  CsvFile csv(path);
  std::vector<ImuSample> out;
  CsvFile::Row row;
  std::int64_t prev_ns = -1;
  int prev_line = 0;
  while (csv.next(row)) {
    csv.expectColumns(row, 7);
    const std::int64_t ns = csv.toInt64(row, 0, kNames[0]);
    if (ns < 0) csv.fail(row.line, "negative timestamp " + std::to_string(ns));
    if (ns <= prev_ns)
      csv.fail(row.line, "timestamps not increasing (line " + std::to_string(row.line) + ": " + std::to_string(ns) +
                             " ns after line " + std::to_string(prev_line) + ": " + std::to_string(prev_ns) + " ns)");
    ImuSample s;
    s.utime = nsToUtime(ns);
    if (!out.empty() && s.utime <= out.back().utime)
      csv.fail(row.line, "timestamp " + std::to_string(ns) + " ns rounds to the same microsecond as line " +
                             std::to_string(prev_line));
    for (int i = 0; i < 3; ++i) s.gyro[i] = csv.toDouble(row, static_cast<std::size_t>(1 + i), kNames[1 + i]);
    for (int i = 0; i < 3; ++i) s.accel[i] = csv.toDouble(row, static_cast<std::size_t>(4 + i), kNames[4 + i]);
    out.push_back(s);
    prev_ns = ns;
    prev_line = row.line;
  }
  if (out.empty()) throw DatasetError(path + ": no IMU rows");
  return out;
}

std::vector<EurocImageEntry> readEurocImageCsv(const std::string& csv_path, const std::string& data_dir) {
  CsvFile csv(csv_path);
  if (!fs::is_directory(data_dir)) throw DatasetError(data_dir + ": missing image folder");
  std::vector<EurocImageEntry> out;
  CsvFile::Row row;
  std::int64_t prev_ns = -1;
  int prev_line = 0;
  while (csv.next(row)) {
    csv.expectColumns(row, 2);
    const std::int64_t ns = csv.toInt64(row, 0, "timestamp_ns");
    if (ns < 0) csv.fail(row.line, "negative timestamp " + std::to_string(ns));
    if (ns <= prev_ns)
      csv.fail(row.line, "timestamps not increasing (line " + std::to_string(row.line) + ": " + std::to_string(ns) +
                             " ns after line " + std::to_string(prev_line) + ": " + std::to_string(prev_ns) + " ns)");
    const std::string name(row.fields[1]);
    if (name.empty()) csv.fail(row.line, "column 2 (filename): empty");
    EurocImageEntry e;
    e.utime = nsToUtime(ns);
    if (!out.empty() && e.utime <= out.back().utime)
      csv.fail(row.line, "timestamp " + std::to_string(ns) + " ns rounds to the same microsecond as line " +
                             std::to_string(prev_line));
    e.path = (fs::path(data_dir) / name).string();
    e.line = row.line;
    if (!fs::is_regular_file(e.path))
      throw DatasetError(e.path + ": missing image (listed in " + csv_path + ":" + std::to_string(row.line) + ")");
    out.push_back(std::move(e));
    prev_ns = ns;
    prev_line = row.line;
  }
  if (out.empty()) throw DatasetError(csv_path + ": no image rows");
  return out;
}

Image readGrayImage(const std::string& path, Utime utime) {
  cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (m.empty()) throw DatasetError(path + ": cannot decode the image");
  if (m.depth() != CV_8U)
    throw DatasetError(path + ": unsupported pixel depth (expected 8-bit gray, got OpenCV depth " +
                       std::to_string(m.depth()) + ")");
  if (m.channels() == 3)
    cv::cvtColor(m, m, cv::COLOR_BGR2GRAY);
  else if (m.channels() == 4)
    cv::cvtColor(m, m, cv::COLOR_BGRA2GRAY);
  else if (m.channels() != 1)
    throw DatasetError(path + ": unsupported channel count " + std::to_string(m.channels()));
  Image img;
  img.utime = utime;
  img.width = m.cols;
  img.height = m.rows;
  img.row_stride = m.cols;
  img.format = PixelFormat::Gray8;
  img.data.resize(static_cast<std::size_t>(m.cols) * static_cast<std::size_t>(m.rows));
  for (int r = 0; r < m.rows; ++r)
    std::memcpy(img.data.data() + static_cast<std::size_t>(r) * static_cast<std::size_t>(m.cols), m.ptr(r),
                static_cast<std::size_t>(m.cols));
  return img;
}

}  // namespace livo
