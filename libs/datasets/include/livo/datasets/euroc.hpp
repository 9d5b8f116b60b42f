// EuRoC / ASL dataset folders (mav0/cam0 + mav0/imu0) to an LCM log and a rig config snippet.
//
// Layout read (DIR may be the dataset root holding mav0/ or the mav0 folder itself):
//   mav0/cam0/data.csv      "#timestamp [ns],filename"                     -> LIVO_CAMERA (GRAY8 image_t)
//   mav0/cam0/data/*.png    8-bit gray images (colour ones are converted to gray)
//   mav0/cam0/sensor.yaml   resolution, intrinsics, distortion, T_BS (pose of the camera in the body frame)
//   mav0/imu0/data.csv      "timestamp_ns, w_x, w_y, w_z, a_x, a_y, a_z"   -> LIVO_IMU (imu_t)
//   mav0/imu0/sensor.yaml   noise densities, rate, T_BS
// Times: utime = round(timestamp_ns / 1000). The log holds every event in time order (IMU before camera at
// equal times) with log timestamp = message utime.
// Time window: images in [start, end] (default: all images); IMU in [start - imu_margin, end + imu_margin]
// (default margin 1 s), because the IMU csv often covers far more than the images.
#pragma once

#include "livo/common/modes.hpp"
#include "livo/common/types.hpp"
#include "livo/datasets/conversion.hpp"

#include <Eigen/Geometry>

#include <optional>
#include <string>
#include <vector>

namespace livo {

struct EurocCameraCalibration {
  int width = 0;   ///< pixels
  int height = 0;  ///< pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< pixels
  CameraKind model = CameraKind::Pinhole;  ///< suite camera model: pinhole (radtan) | equidistant
  std::vector<double> distortion;         ///< radtan [k1, k2, p1, p2] or equidistant [k1, k2, k3, k4]
  double rate_hz = 0;
  Eigen::Isometry3d T_body_camera = Eigen::Isometry3d::Identity();  ///< sensor.yaml T_BS
};

struct EurocImuCalibration {
  double rate_hz = 0;
  double gyro_noise = 0;       ///< rad/s/sqrt(Hz)   (gyroscope_noise_density)
  double accel_noise = 0;      ///< m/s^2/sqrt(Hz)   (accelerometer_noise_density)
  double gyro_bias_walk = 0;   ///< rad/s^2/sqrt(Hz) (gyroscope_random_walk)
  double accel_bias_walk = 0;  ///< m/s^3/sqrt(Hz)   (accelerometer_random_walk)
  Eigen::Isometry3d T_body_imu = Eigen::Isometry3d::Identity();  ///< sensor.yaml T_BS
};

struct EurocCalibration {
  EurocCameraCalibration camera;
  EurocImuCalibration imu;
  /// Pose of the camera in the IMU frame: T_imu_camera = T_body_imu^-1 * T_body_camera.
  Eigen::Isometry3d T_imu_camera() const { return imu.T_body_imu.inverse() * camera.T_body_camera; }
};

/// One row of cam0/data.csv.
struct EurocImageEntry {
  Utime utime = 0;
  std::string path;  ///< image file (checked to exist)
  int line = 0;      ///< line in data.csv (for error messages)
};

struct EurocOptions {
  std::string camera = "cam0";  ///< sensor folder names under mav0/
  std::string imu = "imu0";
  std::string imu_channel = "LIVO_IMU";
  std::string camera_channel = "LIVO_CAMERA";
  /// Window limits in seconds: values below kAbsoluteTimeThreshold_s are relative to the first image,
  /// larger ones are absolute sensor times. Unset: first / last image.
  std::optional<double> start_s;
  std::optional<double> end_s;
  double imu_margin_s = 1.0;  ///< s, IMU kept this long before the window start and after its end
  ProgressFn progress;        ///< called per written image
};

/// Window limits at or above this value (s, about 3 years) are absolute sensor times.
constexpr double kAbsoluteTimeThreshold_s = 1e8;

/// Time window of a conversion (inclusive bounds, microseconds).
struct EurocWindow {
  Utime image_begin = 0, image_end = 0;
  Utime imu_begin = 0, imu_end = 0;
};
/// Throws DatasetError when the window is empty or inverted.
EurocWindow eurocWindow(Utime first_image, Utime last_image, const EurocOptions& opt);

/// round(ns / 1000) for ns >= 0.
Utime nsToUtime(std::int64_t ns);

/// DIR/mav0 when it exists, else DIR when it holds the sensor folders; throws naming what is missing.
std::string eurocMavDir(const std::string& dir, const EurocOptions& opt = {});

/// Parses <mav>/<camera>/sensor.yaml and <mav>/<imu>/sensor.yaml (the "%YAML:1.0" header is skipped).
/// Missing keys or unsupported models throw DatasetError naming the file and the key.
EurocCalibration readEurocCalibration(const std::string& mav_dir, const EurocOptions& opt = {});
EurocCameraCalibration readEurocCameraYaml(const std::string& path);
EurocImuCalibration readEurocImuYaml(const std::string& path);

/// Every row of an IMU data.csv; timestamps must increase strictly (errors name file and line).
std::vector<ImuSample> readEurocImuCsv(const std::string& path);
/// Every row of a camera data.csv; image files are looked up in `data_dir` and must exist.
std::vector<EurocImageEntry> readEurocImageCsv(const std::string& csv_path, const std::string& data_dir);
/// Decodes an image file into an 8-bit gray Image (colour converted to gray); throws naming the file.
Image readGrayImage(const std::string& path, Utime utime);

/// Converts the folder into `out_log`. Nothing is left at `out_log` when it throws.
ConversionSummary convertEuroc(const std::string& dir, const std::string& out_log, const EurocOptions& opt = {});

/// A rig config (sections imu and camera, config/README.md) from the calibration; `source` is named in
/// the header comment. There is no LiDAR in EuRoC: the lidar section is absent (noted in a comment).
std::string eurocRigYaml(const EurocCalibration& calib, const std::string& source);

}  // namespace livo
