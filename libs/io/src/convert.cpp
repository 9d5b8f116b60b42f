#include "livo/io/convert.hpp"

#include <livo/estimator_stats_t.hpp>
#include <livo/filter_state_t.hpp>
#include <livo/resume_request_t.hpp>
#include <livo/resume_t.hpp>
#include <livo/map_correction_t.hpp>
#include <livo/map_query_t.hpp>
#include <livo/map_stats_t.hpp>
#include <livo/map_update_t.hpp>
#include <livo/odometry_t.hpp>
#include <livo/patch_t.hpp>
#include <livo/plane_t.hpp>
#include <livo/registered_scan_t.hpp>
#include <livo/submap_t.hpp>
#include <livo/visual_point_t.hpp>

#include <cmath>
#include <utility>

namespace livo {
namespace {

bool finite3(const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

template <class Vec>
Validation checkSize(const Vec& v, std::int64_t n, const std::string& field, const std::string& count) {
  if (static_cast<std::int64_t>(v.size()) != n)
    return Validation::fail(field + ": " + count + " declares " + std::to_string(n) + " but the array has " +
                            std::to_string(v.size()) + " values");
  return Validation::ok();
}

#define LIVO_CHECK(expr)           \
  do {                             \
    Validation v_ = (expr);        \
    if (!v_) return v_;            \
  } while (0)

}  // namespace

// ---------------- IMU ----------------
livo::imu_t toMsg(const ImuSample& s) {
  livo::imu_t m{};
  m.utime = s.utime;
  for (int i = 0; i < 3; ++i) {
    m.angular_velocity[i] = s.gyro[i];
    m.linear_acceleration[i] = s.accel[i];
  }
  return m;
}

Validation validate(const livo::imu_t& m) {
  if (!finite3(m.angular_velocity)) return Validation::fail("imu_t.angular_velocity: non-finite value");
  if (!finite3(m.linear_acceleration)) return Validation::fail("imu_t.linear_acceleration: non-finite value");
  if (m.utime < 0) return Validation::fail("imu_t.utime: negative time " + std::to_string(m.utime));
  return Validation::ok();
}

Validation fromMsg(const livo::imu_t& m, ImuSample& out) {
  LIVO_CHECK(validate(m));
  out.utime = m.utime;
  out.gyro = Eigen::Vector3d(m.angular_velocity[0], m.angular_velocity[1], m.angular_velocity[2]);
  out.accel = Eigen::Vector3d(m.linear_acceleration[0], m.linear_acceleration[1], m.linear_acceleration[2]);
  return Validation::ok();
}

// ---------------- LiDAR ----------------
livo::lidar_scan_t toMsg(const LidarScan& s) {
  livo::lidar_scan_t m{};
  m.utime = s.utime;
  m.sensor = s.sensor;
  const std::size_t n = s.points.size();
  m.num_points = static_cast<std::int32_t>(n);
  m.x.resize(n); m.y.resize(n); m.z.resize(n);
  m.time_offset_s.resize(n); m.intensity.resize(n); m.ring.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& p = s.points[i];
    m.x[i] = p.p_lidar.x(); m.y[i] = p.p_lidar.y(); m.z[i] = p.p_lidar.z();
    m.time_offset_s[i] = p.time_offset_s; m.intensity[i] = p.intensity; m.ring[i] = p.ring;
  }
  return m;
}

Validation validate(const livo::lidar_scan_t& m, const MessageLimits& lim) {
  const std::string t = "lidar_scan_t.";
  if (m.num_points < 0) return Validation::fail(t + "num_points: negative count " + std::to_string(m.num_points));
  if (m.num_points > lim.max_points)
    return Validation::fail(t + "num_points: " + std::to_string(m.num_points) + " exceeds the limit " +
                            std::to_string(lim.max_points));
  LIVO_CHECK(checkSize(m.x, m.num_points, t + "x", "num_points"));
  LIVO_CHECK(checkSize(m.y, m.num_points, t + "y", "num_points"));
  LIVO_CHECK(checkSize(m.z, m.num_points, t + "z", "num_points"));
  LIVO_CHECK(checkSize(m.time_offset_s, m.num_points, t + "time_offset_s", "num_points"));
  LIVO_CHECK(checkSize(m.intensity, m.num_points, t + "intensity", "num_points"));
  LIVO_CHECK(checkSize(m.ring, m.num_points, t + "ring", "num_points"));
  if (m.utime < 0) return Validation::fail(t + "utime: negative time " + std::to_string(m.utime));
  // LCM encodes strings up to the first NUL: an embedded one would not survive a re-encoding.
  if (m.sensor.find('\0') != std::string::npos) return Validation::fail(t + "sensor: embedded NUL character");
  if (m.sensor.size() > 256) return Validation::fail(t + "sensor: longer than 256 characters");
  // Per-point times must be usable: a scan longer than 10 s or before its start by > 1 s is corrupt.
  for (std::int32_t i = 0; i < m.num_points; ++i) {
    const float dt = m.time_offset_s[i];
    if (!std::isfinite(dt) || dt < -1.0f || dt > 10.0f)
      return Validation::fail(t + "time_offset_s[" + std::to_string(i) + "]: invalid offset " + std::to_string(dt) +
                              " s (expected 0..10 s)");
  }
  return Validation::ok();
}

Validation fromMsg(const livo::lidar_scan_t& m, LidarScan& out, const MessageLimits& lim, std::size_t* dropped) {
  LIVO_CHECK(validate(m, lim));
  out.utime = m.utime;
  out.sensor = m.sensor;
  out.points.clear();
  out.points.reserve(static_cast<std::size_t>(m.num_points));
  std::size_t bad = 0;
  for (std::int32_t i = 0; i < m.num_points; ++i) {
    if (!std::isfinite(m.x[i]) || !std::isfinite(m.y[i]) || !std::isfinite(m.z[i])) {
      ++bad;  // NaN / inf returns are dropped and counted, never an error for the whole scan
      continue;
    }
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(m.x[i], m.y[i], m.z[i]);
    p.time_offset_s = m.time_offset_s[i];
    p.intensity = std::isfinite(m.intensity[i]) ? m.intensity[i] : 0.f;
    p.ring = m.ring[i];
    out.points.push_back(p);
  }
  if (dropped) *dropped = bad;
  return Validation::ok();
}

// ---------------- Image ----------------
namespace {
livo::image_t imageHeader(const Image& img) {
  livo::image_t m{};
  m.utime = img.utime;
  m.width = img.width;
  m.height = img.height;
  m.row_stride = img.row_stride;
  m.pixel_format = static_cast<std::int8_t>(img.format);
  m.exposure_time_s = img.exposure_time_s;
  m.size = static_cast<std::int32_t>(img.data.size());
  return m;
}
}  // namespace

livo::image_t toMsg(const Image& img) {
  livo::image_t m = imageHeader(img);
  m.data = img.data;
  return m;
}

livo::image_t toMsg(Image&& img) {
  livo::image_t m = imageHeader(img);
  m.data = std::move(img.data);
  return m;
}

Validation validate(const livo::image_t& m, const MessageLimits& lim) {
  const std::string t = "image_t.";
  if (m.size < 0) return Validation::fail(t + "size: negative count " + std::to_string(m.size));
  LIVO_CHECK(checkSize(m.data, m.size, t + "data", "size"));
  if (m.width <= 0 || m.height <= 0)
    return Validation::fail(t + "width/height: invalid size " + std::to_string(m.width) + "x" + std::to_string(m.height));
  if (m.width > lim.max_image_side || m.height > lim.max_image_side)
    return Validation::fail(t + "width/height: " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                            " exceeds max_image_side " + std::to_string(lim.max_image_side));
  if (m.pixel_format < 0 || m.pixel_format > 5)
    return Validation::fail(t + "pixel_format: unknown format " + std::to_string(m.pixel_format));
  if (!std::isfinite(m.exposure_time_s) || m.exposure_time_s < 0)
    return Validation::fail(t + "exposure_time_s: invalid value " + std::to_string(m.exposure_time_s));
  const int bpp = bytesPerPixel(static_cast<PixelFormat>(m.pixel_format));
  if (bpp > 0) {
    if (m.row_stride < std::int64_t(m.width) * bpp)
      return Validation::fail(t + "row_stride: " + std::to_string(m.row_stride) + " is smaller than width * " +
                              std::to_string(bpp));
    const std::int64_t need = std::int64_t(m.row_stride) * m.height;
    if (m.size < need)
      return Validation::fail(t + "size: " + std::to_string(m.size) + " bytes, but row_stride * height = " +
                              std::to_string(need));
  } else if (m.size == 0) {
    return Validation::fail(t + "size: empty compressed image");
  }
  return Validation::ok();
}

namespace {
void imageHeaderFromMsg(const livo::image_t& m, Image& out) {
  out.utime = m.utime;
  out.width = m.width;
  out.height = m.height;
  out.row_stride = m.row_stride;
  out.format = static_cast<PixelFormat>(m.pixel_format);
  out.exposure_time_s = m.exposure_time_s;
}
}  // namespace

Validation fromMsg(const livo::image_t& m, Image& out, const MessageLimits& lim) {
  LIVO_CHECK(validate(m, lim));
  imageHeaderFromMsg(m, out);
  out.data = m.data;
  return Validation::ok();
}

Validation fromMsg(livo::image_t&& m, Image& out, const MessageLimits& lim) {
  LIVO_CHECK(validate(m, lim));
  imageHeaderFromMsg(m, out);
  out.data = std::move(m.data);
  m.data = {};
  m.size = 0;
  return Validation::ok();
}

// ---------------- Frame ----------------
livo::frame_t toMsg(const Frame& f) {
  livo::frame_t m{};
  m.utime = f.utime;
  m.sweep_start_utime = f.sweep_start_utime;
  m.num_imu = static_cast<std::int32_t>(f.imu.size());
  m.imu.reserve(f.imu.size());
  for (const auto& s : f.imu) m.imu.push_back(toMsg(s));
  m.sweep = toMsg(f.sweep);
  m.has_image = f.has_image;
  if (f.has_image) {
    m.image = toMsg(f.image);
  } else {
    m.image = livo::image_t();
    m.image.size = 0;
  }
  return m;
}

Validation validate(const livo::frame_t& m, const MessageLimits& lim) {
  const std::string t = "frame_t.";
  if (m.num_imu < 0) return Validation::fail(t + "num_imu: negative count " + std::to_string(m.num_imu));
  if (m.num_imu > lim.max_imu_per_frame)
    return Validation::fail(t + "num_imu: " + std::to_string(m.num_imu) + " exceeds the limit");
  LIVO_CHECK(checkSize(m.imu, m.num_imu, t + "imu", "num_imu"));
  for (std::int32_t i = 0; i < m.num_imu; ++i) {
    Validation v = validate(m.imu[i]);
    if (!v) return Validation::fail(t + "imu[" + std::to_string(i) + "]." + v.error.substr(v.error.find('.') + 1));
    if (i > 0 && m.imu[i].utime < m.imu[i - 1].utime)
      return Validation::fail(t + "imu[" + std::to_string(i) + "].utime: IMU samples out of order");
  }
  if (m.utime < m.sweep_start_utime)
    return Validation::fail(t + "utime: frame end " + std::to_string(m.utime) + " before sweep start " +
                            std::to_string(m.sweep_start_utime));
  Validation vs = validate(m.sweep, lim);
  if (!vs) return Validation::fail(t + "sweep." + vs.error.substr(vs.error.find('.') + 1));
  if (m.has_image) {
    Validation vi = validate(m.image, lim);
    if (!vi) return Validation::fail(t + "image." + vi.error.substr(vi.error.find('.') + 1));
    if (m.image.pixel_format != livo::image_t::GRAY8)
      return Validation::fail(t + "image.pixel_format: frames carry GRAY8 images");
  }
  return Validation::ok();
}

Validation fromMsg(const livo::frame_t& m, Frame& out, const MessageLimits& lim, std::size_t* dropped) {
  LIVO_CHECK(validate(m, lim));
  out.utime = m.utime;
  out.sweep_start_utime = m.sweep_start_utime;
  out.imu.resize(static_cast<std::size_t>(m.num_imu));
  for (std::int32_t i = 0; i < m.num_imu; ++i) fromMsg(m.imu[i], out.imu[static_cast<std::size_t>(i)]);
  fromMsg(m.sweep, out.sweep, lim, dropped);
  out.has_image = m.has_image;
  out.image = Image();
  if (m.has_image) fromMsg(m.image, out.image, lim);
  return Validation::ok();
}

// ---------------- decode ----------------
template <class Msg>
Validation decode(const void* data, std::size_t size, Msg& out, const MessageLimits& lim) {
  Validation v = precheck<Msg>(data, size, lim);
  if (!v) return v;
  if (out.decode(data, 0, static_cast<int>(size)) < 0)
    return Validation::fail(std::string(Msg::getTypeName()) + ": decode failed");
  return Validation::ok();
}

template Validation decode(const void*, std::size_t, livo::imu_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::lidar_scan_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::image_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::frame_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::map_query_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::plane_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::patch_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::visual_point_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::submap_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::map_update_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::odometry_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::registered_scan_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::estimator_stats_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::map_stats_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::filter_state_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::resume_request_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::resume_t&, const MessageLimits&);
template Validation decode(const void*, std::size_t, livo::map_correction_t&, const MessageLimits&);

}  // namespace livo
