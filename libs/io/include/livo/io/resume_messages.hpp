// Conversions of the restart protocol (filter_state_t, resume_request_t, resume_t): the estimator
// publishes its whole filter state after every frame; the map server keeps the latest and the IMU
// samples after it, and answers a (re)starting estimator's request with both (EstimatorNode,
// MapServerNode). Validation as in convert.hpp: fromMsg() leaves `out` untouched on failure and names
// the field.
#pragma once

#include "livo/estimation/lio_odometry.hpp"
#include "livo/io/convert.hpp"

#include <livo/filter_state_t.hpp>
#include <livo/resume_t.hpp>

#include <cstdint>
#include <vector>

namespace livo {

/// The filter state a frame ended with (filter_state_t).
struct FilterSnapshot {
  FilterState filter;        ///< state (its utime is the message's), covariance, accelerometer units
  std::int64_t frames = 0;   ///< frames the sending estimator processed
};

/// The map server's answer to a starting estimator (resume_t).
struct ResumeAnswer {
  std::int64_t request_id = 0;
  bool have_state = false;
  FilterSnapshot snapshot;          ///< valid when have_state
  std::vector<ImuSample> imu;       ///< after snapshot's time, time ordered
  std::int64_t imu_dropped = 0;     ///< samples after it the map server no longer held
  /// The keys whose values differ between the asking estimator's config and the map server's
  /// ("key: A here, B there; ..."); empty when they agree.
  std::string config_mismatch;
};

/// The state is symmetrised ((P + P^T) / 2) on the way out.
livo::filter_state_t toMsg(const FilterSnapshot& s);
livo::resume_t toMsg(const ResumeAnswer& a);

/// filter_state_t: finite state, unit-normable quaternion, inv_exposure > 0, accel_scale in (0, 20],
/// a covariance that passes the covariance check (symmetric, non-negative variances, |c_ij| bounded).
Validation fromMsg(const livo::filter_state_t& m, FilterSnapshot& out);
/// resume_t: the state (when have_state), num_imu in [0, lim.max_imu_per_frame] matching the array,
/// every sample valid and after the state's time, in time order; imu_dropped >= 0.
Validation fromMsg(const livo::resume_t& m, ResumeAnswer& out, const MessageLimits& lim = {});

}  // namespace livo
