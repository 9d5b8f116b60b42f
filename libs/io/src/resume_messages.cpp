#include "livo/io/resume_messages.hpp"

#include "message_checks.hpp"

#include <cmath>

namespace livo {

namespace {

using namespace msgcheck;

Validation checkState(const livo::filter_state_t& m) {
  LIVO_MSG_CHECK(navState(m));
  if (!std::isfinite(m.time_offset_s))
    return Validation::fail("time_offset_s: expected a finite value, got " + num(m.time_offset_s));
  if (!std::isfinite(m.accel_scale) || !(m.accel_scale > 0.0) || m.accel_scale > 20.0)
    return Validation::fail("accel_scale: expected a value in (0, 20], got " + num(m.accel_scale));
  LIVO_MSG_CHECK(covariance(&m.covariance[0][0], kStateDim, "covariance"));
  if (m.frames < 0) return Validation::fail("frames: negative count " + std::to_string(m.frames));
  return Validation::ok();
}

}  // namespace

livo::filter_state_t toMsg(const FilterSnapshot& s) {
  const NavState& x = s.filter.state;
  livo::filter_state_t m{};
  m.utime = x.utime;
  Pose T = Pose::Identity();
  T.linear() = x.R_world_imu;
  T.translation() = x.p_world_imu;
  const auto a = poseToArray(T);
  for (int i = 0; i < 3; ++i) {
    m.position[i] = a[std::size_t(i)];
    m.velocity[i] = x.v_world[i];
    m.gyro_bias[i] = x.bg[i];
    m.accel_bias[i] = x.ba[i];
    m.gravity[i] = x.g_world[i];
  }
  for (int i = 0; i < 4; ++i) m.orientation[i] = a[std::size_t(3 + i)];
  m.inv_exposure = x.inv_exposure;
  m.time_offset_s = x.time_offset_s;
  m.accel_scale = s.filter.accel_scale;
  for (int i = 0; i < kStateDim; ++i)
    for (int j = 0; j < kStateDim; ++j) m.covariance[i][j] = 0.5 * (s.filter.P(i, j) + s.filter.P(j, i));
  m.frames = s.frames;
  return m;
}

Validation fromMsg(const livo::filter_state_t& m, FilterSnapshot& out) {
  LIVO_MSG_CHECK(nest(checkState(m), "filter_state_t"));
  const double a[7] = {m.position[0],    m.position[1],    m.position[2],   m.orientation[0],
                       m.orientation[1], m.orientation[2], m.orientation[3]};
  const Pose T = poseFromArray(a);
  FilterSnapshot s;
  NavState& x = s.filter.state;
  x.utime = m.utime;
  x.R_world_imu = T.linear();
  x.p_world_imu = T.translation();
  x.inv_exposure = m.inv_exposure;
  x.v_world = Vec3(m.velocity[0], m.velocity[1], m.velocity[2]);
  x.bg = Vec3(m.gyro_bias[0], m.gyro_bias[1], m.gyro_bias[2]);
  x.ba = Vec3(m.accel_bias[0], m.accel_bias[1], m.accel_bias[2]);
  x.g_world = Vec3(m.gravity[0], m.gravity[1], m.gravity[2]);
  x.time_offset_s = m.time_offset_s;
  s.filter.accel_scale = m.accel_scale;
  for (int i = 0; i < kStateDim; ++i)
    for (int j = 0; j < kStateDim; ++j) s.filter.P(i, j) = m.covariance[i][j];
  s.frames = m.frames;
  out = std::move(s);
  return Validation::ok();
}

livo::resume_t toMsg(const ResumeAnswer& a) {
  livo::resume_t m{};
  m.request_id = a.request_id;
  m.have_state = a.have_state;
  m.state = toMsg(a.snapshot);
  m.num_imu = std::int32_t(a.imu.size());
  m.imu.reserve(a.imu.size());
  for (const ImuSample& s : a.imu) m.imu.push_back(toMsg(s));
  m.imu_dropped = a.imu_dropped;
  m.config_mismatch = a.config_mismatch;
  return m;
}

Validation fromMsg(const livo::resume_t& m, ResumeAnswer& out, const MessageLimits& lim) {
  ResumeAnswer a;
  a.request_id = m.request_id;
  a.have_state = m.have_state;
  if (m.have_state) LIVO_MSG_CHECK(nest(fromMsg(m.state, a.snapshot), "resume_t.state"));
  LIVO_MSG_CHECK(nest(count(m.num_imu, lim.max_imu_per_frame, "num_imu", "max_imu_per_frame"), "resume_t"));
  LIVO_MSG_CHECK(nest(size(m.imu, m.num_imu, "imu", "num_imu"), "resume_t"));
  if (m.imu_dropped < 0)
    return Validation::fail("resume_t.imu_dropped: negative count " + std::to_string(m.imu_dropped));
  a.imu.reserve(std::size_t(m.num_imu));
  for (std::int32_t i = 0; i < m.num_imu; ++i) {
    ImuSample s;
    LIVO_MSG_CHECK(nest(fromMsg(m.imu[std::size_t(i)], s), "resume_t.imu[" + std::to_string(i) + "]"));
    const Utime prev = a.imu.empty() ? (a.have_state ? a.snapshot.filter.state.utime : -1) : a.imu.back().utime;
    if (s.utime <= prev)
      return Validation::fail("resume_t.imu[" + std::to_string(i) + "].utime: " + std::to_string(s.utime) +
                              " not after " + std::to_string(prev) + " (samples must follow the state, in time order)");
    a.imu.push_back(s);
  }
  a.imu_dropped = m.imu_dropped;
  a.config_mismatch = m.config_mismatch;
  out = std::move(a);
  return Validation::ok();
}

}  // namespace livo
