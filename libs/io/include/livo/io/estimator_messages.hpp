// Conversions between the estimator's outputs and their messages (odometry_t, registered_scan_t,
// estimator_stats_t), with validation in the pattern of convert.hpp: toMsg() sets every count from the
// vectors; fromMsg() validates first and leaves `out` untouched on failure; validate() names the field,
// e.g. "odometry_t.covariance: negative variance -0.1 at (3,3)".
#pragma once

#include "livo/estimation/state.hpp"
#include "livo/io/convert.hpp"

#include <livo/estimator_stats_t.hpp>
#include <livo/odometry_t.hpp>
#include <livo/registered_scan_t.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace livo {

/// Bits of OdometryOutput::status (the STATUS_* constants of odometry_t).
namespace odometry_status {
constexpr std::int32_t kInitializing = 1;
constexpr std::int32_t kDegenerate = 2;
constexpr std::int32_t kVisualUpdate = 4;
constexpr std::int32_t kMapTimeout = 8;
constexpr std::int32_t kLidarFailed = 16;
constexpr std::int32_t kLidarUpdate = 32;  ///< the LiDAR update was applied to this frame
constexpr std::int32_t kDegraded = 64;     ///< a consistency check is out of its bound (health.hpp)
constexpr std::int32_t kLost = 128;        ///< the estimate is not trusted
constexpr std::int32_t kKnownBits = 255;  ///< any other bit set is a validation error
}  // namespace odometry_status

/// Estimator output per frame (odometry_t). `state.utime` is sent as `utime` (toMsg uses `utime`;
/// fromMsg sets both). pose_cov is the [rotation (rad), position (m)] block of the state covariance,
/// right perturbation (StateCov rows/cols 0..5).
struct OdometryOutput {
  Utime utime = 0;
  NavState state;
  Mat6 pose_cov = Mat6::Zero();
  std::int32_t status = 0;  ///< bit set of odometry_status::k*
};

/// The frame's undistorted, downsampled points in the world frame (registered_scan_t).
struct RegisteredScan {
  Utime utime = 0;
  std::vector<Eigen::Vector3f> points;  ///< world frame, m
  std::vector<float> intensity;         ///< same size as points
  std::vector<std::int32_t> rgb;        ///< empty, or same size: 0xRRGGBB, -1 when not seen
};

/// Per-frame timing and health (estimator_stats_t).
struct EstimatorStats {
  Utime utime = 0;
  std::int64_t frame_index = 0;
  float lio_ms = 0.f;    ///< propagation + undistortion + LiDAR update
  float vio_ms = 0.f;    ///< visual update (0 when not run)
  float map_ms = 0.f;    ///< the map's work in the estimator's process (frame_row.hpp)
  float map_wait_ms = 0.f;  ///< waiting for the map server's answers (0 in one process)
  float total_ms = 0.f;
  float sigma_min = 0.f; ///< normalised smallest singular value of sum n n^T
  bool degenerate = false;
  bool visual_used = false;
  bool map_timeout = false;
  bool lidar_failed = false;  ///< the LiDAR update failed on a map that should have matched
  std::int32_t n_points = 0;          ///< downsampled points used
  std::int32_t n_planes_matched = 0;
  std::int32_t n_visual_points = 0;   ///< visual points used in the update
  std::int32_t n_longterm_visual_points = 0;  ///< of those, points that came through the long-term map
  bool has_time_offset = false;  ///< camera.estimate_time_offset: the camera's time offset estimate, s
  double time_offset_s = 0.0, time_offset_sigma_s = 0.0;
  std::int32_t dropped_points = 0;    ///< NaN / out of range / blind
  // Load (livo-estimator; EstimatorNode sheds under overload).
  float lag_ms = 0.f;                 ///< frame arrival -> outputs published, wall clock
  std::int32_t frames_shed = 0;       ///< frames dropped just before this one (their IMU merged into it)
  bool image_shed = false;            ///< the frame's image was left out
  /// The filter's health: 0 initialising, 1 ok, 2 degraded, 3 lost (HealthState's order), and why.
  std::int8_t health = 0;
  std::string health_reason;
};

// ---- struct -> message. RegisteredScan with intensity of another size than points, or rgb neither
// empty nor of that size, throws std::invalid_argument naming the field. ----
livo::odometry_t toMsg(const OdometryOutput& o);
livo::registered_scan_t toMsg(const RegisteredScan& s);
livo::estimator_stats_t toMsg(const EstimatorStats& s);

// ---- message -> struct: validate(), then convert; `out` is untouched on failure. ----
Validation fromMsg(const livo::odometry_t& m, OdometryOutput& out, const MessageLimits& lim = {});
Validation fromMsg(const livo::registered_scan_t& m, RegisteredScan& out, const MessageLimits& lim = {});
Validation fromMsg(const livo::estimator_stats_t& m, EstimatorStats& out, const MessageLimits& lim = {});

// ---- validation. odometry_t: finite state, non-zero quaternion, inv_exposure > 0, covariance finite,
// symmetric, non-negative diagonal, PSD 2x2 minors, only known status bits. registered_scan_t:
// counts match arrays and max_points, num_colors 0 or num_points, finite points and intensities, rgb in
// -1..0xFFFFFF. estimator_stats_t: times finite and >= 0, counts >= 0, sigma_min finite and >= 0. ----
Validation validate(const livo::odometry_t& m, const MessageLimits& lim = {});
Validation validate(const livo::registered_scan_t& m, const MessageLimits& lim = {});
Validation validate(const livo::estimator_stats_t& m, const MessageLimits& lim = {});

}  // namespace livo
