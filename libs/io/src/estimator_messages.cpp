#include "livo/io/estimator_messages.hpp"

#include "message_checks.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace livo {

static_assert(odometry_status::kInitializing == livo::odometry_t::STATUS_INITIALIZING &&
                  odometry_status::kDegenerate == livo::odometry_t::STATUS_DEGENERATE &&
                  odometry_status::kVisualUpdate == livo::odometry_t::STATUS_VISUAL_UPDATE &&
                  odometry_status::kMapTimeout == livo::odometry_t::STATUS_MAP_TIMEOUT &&
                  odometry_status::kLidarFailed == livo::odometry_t::STATUS_LIDAR_FAILED &&
                  odometry_status::kLidarUpdate == livo::odometry_t::STATUS_LIDAR_UPDATE &&
                  odometry_status::kDegraded == livo::odometry_t::STATUS_DEGRADED &&
                  odometry_status::kLost == livo::odometry_t::STATUS_LOST,
              "odometry_status must mirror the STATUS_* constants of lcmtypes/livo_odometry_t.lcm");

namespace {

/// Longest health_reason sent or accepted, bytes.
constexpr std::size_t kMaxHealthReason = 512;

using namespace msgcheck;

Validation checkOdometry(const livo::odometry_t& m) {
  LIVO_MSG_CHECK(navState(m));
  LIVO_MSG_CHECK(covariance(&m.covariance[0][0], 6, "covariance"));
  if ((m.status & ~odometry_status::kKnownBits) != 0)
    return Validation::fail("status: unknown bits in " + std::to_string(m.status) + " (known STATUS_* bits: " +
                            std::to_string(odometry_status::kKnownBits) + ")");
  return Validation::ok();
}

Validation checkRegistered(const livo::registered_scan_t& m, const MessageLimits& lim) {
  LIVO_MSG_CHECK(utime(m.utime));
  LIVO_MSG_CHECK(count(m.num_points, lim.max_points, "num_points", "max_points"));
  LIVO_MSG_CHECK(size(m.x, m.num_points, "x", "num_points"));
  LIVO_MSG_CHECK(size(m.y, m.num_points, "y", "num_points"));
  LIVO_MSG_CHECK(size(m.z, m.num_points, "z", "num_points"));
  LIVO_MSG_CHECK(size(m.intensity, m.num_points, "intensity", "num_points"));
  if (m.num_colors != 0 && m.num_colors != m.num_points)
    return Validation::fail("num_colors: " + std::to_string(m.num_colors) + " but must be 0 or num_points (" +
                            std::to_string(m.num_points) + ")");
  LIVO_MSG_CHECK(size(m.rgb, m.num_colors, "rgb", "num_colors"));
  LIVO_MSG_CHECK(finite(m.x.data(), m.num_points, "x"));
  LIVO_MSG_CHECK(finite(m.y.data(), m.num_points, "y"));
  LIVO_MSG_CHECK(finite(m.z.data(), m.num_points, "z"));
  LIVO_MSG_CHECK(finite(m.intensity.data(), m.num_points, "intensity"));
  for (std::int32_t i = 0; i < m.num_colors; ++i) {
    const std::int32_t c = m.rgb[std::size_t(i)];
    if (c < -1 || c > 0xFFFFFF)
      return Validation::fail("rgb[" + std::to_string(i) + "]: " + std::to_string(c) +
                              " is neither 0xRRGGBB nor -1 (not seen)");
  }
  return Validation::ok();
}

Validation checkStats(const livo::estimator_stats_t& m) {
  LIVO_MSG_CHECK(utime(m.utime));
  if (m.health < 0 || m.health > 3) return Validation::fail("health: " + std::to_string(int(m.health)) + " is not 0..3");
  if (m.health_reason.size() > kMaxHealthReason)
    return Validation::fail("health_reason: " + std::to_string(m.health_reason.size()) + " bytes, above " +
                            std::to_string(kMaxHealthReason));
  if (m.frame_index < 0) return Validation::fail("frame_index: negative " + std::to_string(m.frame_index));
  LIVO_MSG_CHECK(nonNegative(m.lio_ms, "lio_ms"));
  LIVO_MSG_CHECK(nonNegative(m.vio_ms, "vio_ms"));
  LIVO_MSG_CHECK(nonNegative(m.map_ms, "map_ms"));
  LIVO_MSG_CHECK(nonNegative(m.map_wait_ms, "map_wait_ms"));
  LIVO_MSG_CHECK(nonNegative(m.total_ms, "total_ms"));
  LIVO_MSG_CHECK(nonNegative(m.sigma_min, "sigma_min"));
  LIVO_MSG_CHECK(nonNegative(m.lag_ms, "lag_ms"));
  const std::pair<std::int32_t, const char*> counts[] = {{m.n_points, "n_points"},
                                                         {m.n_planes_matched, "n_planes_matched"},
                                                         {m.n_visual_points, "n_visual_points"},
                                                         {m.n_longterm_visual_points, "n_longterm_visual_points"},
                                                         {m.dropped_points, "dropped_points"},
                                                         {m.frames_shed, "frames_shed"}};
  for (const auto& c : counts)
    if (c.first < 0) return Validation::fail(std::string(c.second) + ": negative count " + std::to_string(c.first));
  if (!std::isfinite(m.time_offset_s) || std::abs(m.time_offset_s) > 1e4)
    return Validation::fail("time_offset_s: not a finite offset below 1e4 s");
  if (!(m.time_offset_sigma_s >= 0) || !std::isfinite(m.time_offset_sigma_s))
    return Validation::fail("time_offset_sigma_s: not a finite sigma >= 0");
  if (m.n_longterm_visual_points > m.n_visual_points)
    return Validation::fail("n_longterm_visual_points: " + std::to_string(m.n_longterm_visual_points) +
                            " more than n_visual_points " + std::to_string(m.n_visual_points));
  return Validation::ok();
}

}  // namespace

// ---------------- odometry_t ----------------
livo::odometry_t toMsg(const OdometryOutput& o) {
  livo::odometry_t m{};
  m.utime = o.utime;
  Pose T = Pose::Identity();
  T.linear() = o.state.R_world_imu;
  T.translation() = o.state.p_world_imu;
  const auto a = poseToArray(T);  // [x, y, z, qx, qy, qz, qw], qw >= 0
  for (int i = 0; i < 3; ++i) {
    m.position[i] = a[std::size_t(i)];
    m.velocity[i] = o.state.v_world[i];
    m.gyro_bias[i] = o.state.bg[i];
    m.accel_bias[i] = o.state.ba[i];
    m.gravity[i] = o.state.g_world[i];
  }
  for (int i = 0; i < 4; ++i) m.orientation[i] = a[std::size_t(3 + i)];
  m.inv_exposure = o.state.inv_exposure;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) m.covariance[i][j] = o.pose_cov(i, j);
  m.status = o.status;
  return m;
}

Validation validate(const livo::odometry_t& m, const MessageLimits&) { return nest(checkOdometry(m), "odometry_t"); }

Validation fromMsg(const livo::odometry_t& m, OdometryOutput& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  const double a[7] = {m.position[0],    m.position[1],    m.position[2],   m.orientation[0],
                       m.orientation[1], m.orientation[2], m.orientation[3]};
  const Pose T = poseFromArray(a);
  out.utime = m.utime;
  out.state = NavState();
  out.state.utime = m.utime;
  out.state.R_world_imu = T.linear();
  out.state.p_world_imu = T.translation();
  out.state.inv_exposure = m.inv_exposure;
  out.state.v_world = Vec3(m.velocity[0], m.velocity[1], m.velocity[2]);
  out.state.bg = Vec3(m.gyro_bias[0], m.gyro_bias[1], m.gyro_bias[2]);
  out.state.ba = Vec3(m.accel_bias[0], m.accel_bias[1], m.accel_bias[2]);
  out.state.g_world = Vec3(m.gravity[0], m.gravity[1], m.gravity[2]);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) out.pose_cov(i, j) = m.covariance[i][j];
  out.status = m.status;
  return Validation::ok();
}

// ---------------- registered_scan_t ----------------
livo::registered_scan_t toMsg(const RegisteredScan& s) {
  const std::size_t n = s.points.size();
  if (s.intensity.size() != n)
    throw std::invalid_argument("registered_scan_t.intensity: " + std::to_string(s.intensity.size()) +
                                " values for " + std::to_string(n) + " points");
  if (!s.rgb.empty() && s.rgb.size() != n)
    throw std::invalid_argument("registered_scan_t.rgb: " + std::to_string(s.rgb.size()) + " colours for " +
                                std::to_string(n) + " points (must be 0 or the number of points)");
  livo::registered_scan_t m{};
  m.utime = s.utime;
  m.num_points = static_cast<std::int32_t>(n);
  m.x.resize(n); m.y.resize(n); m.z.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    m.x[i] = s.points[i].x(); m.y[i] = s.points[i].y(); m.z[i] = s.points[i].z();
  }
  m.intensity = s.intensity;
  m.num_colors = static_cast<std::int32_t>(s.rgb.size());
  m.rgb = s.rgb;
  return m;
}

Validation validate(const livo::registered_scan_t& m, const MessageLimits& lim) {
  return nest(checkRegistered(m, lim), "registered_scan_t");
}

Validation fromMsg(const livo::registered_scan_t& m, RegisteredScan& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  out.utime = m.utime;
  out.points.resize(m.x.size());
  for (std::size_t i = 0; i < m.x.size(); ++i) out.points[i] = Eigen::Vector3f(m.x[i], m.y[i], m.z[i]);
  out.intensity = m.intensity;
  out.rgb = m.rgb;
  return Validation::ok();
}

// ---------------- estimator_stats_t ----------------
livo::estimator_stats_t toMsg(const EstimatorStats& s) {
  livo::estimator_stats_t m{};
  m.utime = s.utime;
  m.frame_index = s.frame_index;
  m.lio_ms = s.lio_ms;
  m.vio_ms = s.vio_ms;
  m.map_ms = s.map_ms;
  m.map_wait_ms = s.map_wait_ms;
  m.total_ms = s.total_ms;
  m.sigma_min = s.sigma_min;
  m.degenerate = s.degenerate;
  m.visual_used = s.visual_used;
  m.map_timeout = s.map_timeout;
  m.lidar_failed = s.lidar_failed;
  m.n_points = s.n_points;
  m.n_planes_matched = s.n_planes_matched;
  m.n_visual_points = s.n_visual_points;
  m.n_longterm_visual_points = s.n_longterm_visual_points;
  m.has_time_offset = s.has_time_offset;
  m.time_offset_s = s.time_offset_s;
  m.time_offset_sigma_s = s.time_offset_sigma_s;
  m.dropped_points = s.dropped_points;
  m.lag_ms = s.lag_ms;
  m.frames_shed = s.frames_shed;
  m.image_shed = s.image_shed;
  m.health = s.health;
  m.health_reason = s.health_reason.substr(0, kMaxHealthReason);
  return m;
}

Validation validate(const livo::estimator_stats_t& m, const MessageLimits&) {
  return nest(checkStats(m), "estimator_stats_t");
}

Validation fromMsg(const livo::estimator_stats_t& m, EstimatorStats& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  out.utime = m.utime;
  out.frame_index = m.frame_index;
  out.lio_ms = m.lio_ms;
  out.vio_ms = m.vio_ms;
  out.map_ms = m.map_ms;
  out.map_wait_ms = m.map_wait_ms;
  out.total_ms = m.total_ms;
  out.sigma_min = m.sigma_min;
  out.degenerate = m.degenerate != 0;
  out.visual_used = m.visual_used != 0;
  out.map_timeout = m.map_timeout != 0;
  out.lidar_failed = m.lidar_failed != 0;
  out.n_points = m.n_points;
  out.n_planes_matched = m.n_planes_matched;
  out.n_visual_points = m.n_visual_points;
  out.n_longterm_visual_points = m.n_longterm_visual_points;
  out.has_time_offset = m.has_time_offset != 0;
  out.time_offset_s = m.time_offset_s;
  out.time_offset_sigma_s = m.time_offset_sigma_s;
  out.dropped_points = m.dropped_points;
  out.lag_ms = m.lag_ms;
  out.frames_shed = m.frames_shed;
  out.image_shed = m.image_shed != 0;
  out.health = m.health;
  out.health_reason = m.health_reason;
  return Validation::ok();
}

}  // namespace livo
