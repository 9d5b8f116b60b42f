// Plain measurement structs shared by every library. No middleware types here: processes convert
// LCM messages to these (libs/io) and algorithms only ever see these.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace livo {

/// Time stamps are int64 microseconds of the sensor clock, as in every message (`utime`).
using Utime = std::int64_t;
inline double toSeconds(Utime t) { return static_cast<double>(t) * 1e-6; }
/// Rounds to the nearest microsecond, halves away from zero: std::llround's result, inline (it runs for
/// every LiDAR point several times, and libm's llround was 3 % of a LiDAR-only run's instructions).
inline Utime fromSeconds(double s) {
  const double us = s * 1e6;
  if (!(std::abs(us) < 9.0e18)) return static_cast<Utime>(std::llround(us));  // NaN, out of range: as before
  Utime i = static_cast<Utime>(us);  // towards zero
  const double frac = us - static_cast<double>(i);  // exact
  if (frac >= 0.5) ++i;
  else if (frac <= -0.5) --i;
  return i;
}

/// One IMU sample in the IMU (body) frame.
struct ImuSample {
  Utime utime = 0;
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   ///< angular rate, rad/s
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  ///< specific force, m/s^2 (or g: see initialisation)
};

/// One LiDAR return in the LiDAR frame.
struct LidarPoint {
  Eigen::Vector3f p_lidar = Eigen::Vector3f::Zero();  ///< metres, LiDAR frame
  float time_offset_s = 0.f;  ///< seconds after the owning scan's start time
  float intensity = 0.f;      ///< sensor units
  std::int16_t ring = -1;     ///< ring / line index, -1 when unknown
};

/// A LiDAR scan or recut sweep: points with time offsets relative to `utime` (the start).
struct LidarScan {
  Utime utime = 0;
  std::string sensor;  ///< model name, e.g. "avia", "mid360", "spinning32"
  std::vector<LidarPoint> points;
  /// Time of the last point (utime when empty).
  Utime endUtime() const;
};

/// Pixel formats of raw and compressed camera images.
enum class PixelFormat : std::int8_t { Gray8 = 0, Rgb8 = 1, Bgr8 = 2, Jpeg = 3, Png = 4, Gray16 = 5 };

/// A camera image. Raw formats store rows of `row_stride` bytes; compressed ones the encoded stream.
struct Image {
  Utime utime = 0;  ///< capture time (middle of exposure)
  int width = 0;
  int height = 0;
  int row_stride = 0;  ///< bytes per row for raw formats, 0 for compressed
  PixelFormat format = PixelFormat::Gray8;
  float exposure_time_s = 0.f;  ///< 0 when unknown
  std::vector<std::uint8_t> data;
  bool empty() const { return width == 0 || height == 0 || data.empty(); }
};

/// Bytes per pixel of a raw format, 0 for compressed formats.
int bytesPerPixel(PixelFormat f);
const char* toString(PixelFormat f);

/// One estimator frame: the sweep between the previous frame time and `utime` (the image time when a
/// camera is present), the IMU samples that cover it, and the gray image (if any).
struct Frame {
  Utime utime = 0;              ///< frame time: sweep end = image capture time
  Utime sweep_start_utime = 0;  ///< = previous frame time
  std::vector<ImuSample> imu;   ///< covers [sweep_start, utime], time ordered
  LidarScan sweep;              ///< sweep.utime == sweep_start_utime
  bool has_image = false;
  Image image;                  ///< Gray8 when has_image
};

}  // namespace livo
