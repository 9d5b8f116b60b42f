#include "livo/io/loop_messages.hpp"

#include "message_checks.hpp"

namespace livo {

namespace {

using namespace msgcheck;

void putPose(const Pose& T, double* out) {
  const auto a = poseToArray(T);
  for (int i = 0; i < 7; ++i) out[i] = a[std::size_t(i)];
}

Validation checkCorrection(const livo::map_correction_t& m, const MessageLimits& lim) {
  LIVO_MSG_CHECK(utime(m.utime));
  const double T[7] = {m.position[0],    m.position[1],    m.position[2],   m.orientation[0],
                       m.orientation[1], m.orientation[2], m.orientation[3]};
  LIVO_MSG_CHECK(pose7(T, "position/orientation"));
  LIVO_MSG_CHECK(count(m.keyframes_total, lim.max_keyframes, "keyframes_total", "max_keyframes"));
  if (m.solves < 0) return Validation::fail("solves: negative count " + std::to_string(m.solves));
  LIVO_MSG_CHECK(count(m.first_keyframe, lim.max_keyframes, "first_keyframe", "max_keyframes"));
  LIVO_MSG_CHECK(count(m.num_keyframes, lim.max_keyframes, "num_keyframes", "max_keyframes"));
  if (std::int64_t(m.first_keyframe) + m.num_keyframes > m.keyframes_total)
    return Validation::fail("first_keyframe + num_keyframes: " + std::to_string(m.first_keyframe) + " + " +
                            std::to_string(m.num_keyframes) + " exceeds keyframes_total " +
                            std::to_string(m.keyframes_total));
  LIVO_MSG_CHECK(size(m.keyframe_utime, m.num_keyframes, "keyframe_utime", "num_keyframes"));
  LIVO_MSG_CHECK(size(m.odom_pose, m.num_keyframes, "odom_pose", "num_keyframes"));
  LIVO_MSG_CHECK(size(m.map_pose, m.num_keyframes, "map_pose", "num_keyframes"));
  for (std::int32_t i = 0; i < m.num_keyframes; ++i) {
    const std::size_t k = std::size_t(i);
    const std::string at = "[" + std::to_string(i) + "]";
    if (!utime(m.keyframe_utime[k])) return Validation::fail("keyframe_utime" + at + ": negative time");
    if (i > 0 && m.keyframe_utime[k] <= m.keyframe_utime[k - 1])
      return Validation::fail("keyframe_utime" + at + ": " + std::to_string(m.keyframe_utime[k]) +
                              " is not after the keyframe before it");
    LIVO_MSG_CHECK(nest(pose7(m.odom_pose[k].data(), "pose"), "odom_pose" + at));
    LIVO_MSG_CHECK(nest(pose7(m.map_pose[k].data(), "pose"), "map_pose" + at));
  }
  LIVO_MSG_CHECK(count(m.num_loops, lim.max_keyframes, "num_loops", "max_keyframes"));
  LIVO_MSG_CHECK(size(m.loop_from, m.num_loops, "loop_from", "num_loops"));
  LIVO_MSG_CHECK(size(m.loop_to, m.num_loops, "loop_to", "num_loops"));
  for (std::int32_t i = 0; i < m.num_loops; ++i) {
    const std::int32_t a = m.loop_from[std::size_t(i)], b = m.loop_to[std::size_t(i)];
    if (a < 0 || a >= b || b >= m.keyframes_total)
      return Validation::fail("loop_from/loop_to[" + std::to_string(i) + "]: " + std::to_string(a) + " -> " +
                              std::to_string(b) + " is not 0 <= from < to < keyframes_total (" +
                              std::to_string(m.keyframes_total) + ")");
  }
  return Validation::ok();
}

}  // namespace

livo::map_correction_t toMsg(const MapCorrection& c) {
  livo::map_correction_t m{};
  m.utime = c.utime;
  double T[7];
  putPose(c.T_map_odom, T);
  for (int i = 0; i < 3; ++i) m.position[i] = T[i];
  for (int i = 0; i < 4; ++i) m.orientation[i] = T[3 + i];
  m.keyframes_total = c.keyframes_total;
  m.solves = c.solves;
  m.is_final = c.final;
  m.first_keyframe = c.first;
  m.num_keyframes = std::int32_t(c.keyframes.size());
  m.keyframe_utime.resize(c.keyframes.size());
  m.odom_pose.resize(c.keyframes.size());
  m.map_pose.resize(c.keyframes.size());
  for (std::size_t i = 0; i < c.keyframes.size(); ++i) {
    m.keyframe_utime[i] = c.keyframes[i].utime;
    m.odom_pose[i].resize(7);
    m.map_pose[i].resize(7);
    putPose(c.keyframes[i].T_odom, m.odom_pose[i].data());
    putPose(c.keyframes[i].T_map, m.map_pose[i].data());
  }
  m.num_loops = std::int32_t(c.loops.size());
  for (const auto& [a, b] : c.loops) {
    m.loop_from.push_back(a);
    m.loop_to.push_back(b);
  }
  return m;
}

Validation fromMsg(const livo::map_correction_t& m, MapCorrection& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(nest(checkCorrection(m, lim), "map_correction_t"));
  MapCorrection c;
  c.utime = m.utime;
  const double T[7] = {m.position[0],    m.position[1],    m.position[2],   m.orientation[0],
                       m.orientation[1], m.orientation[2], m.orientation[3]};
  c.T_map_odom = poseFromArray(T);
  c.keyframes_total = m.keyframes_total;
  c.solves = m.solves;
  c.final = m.is_final;
  c.first = m.first_keyframe;
  c.keyframes.resize(std::size_t(m.num_keyframes));
  for (std::size_t i = 0; i < c.keyframes.size(); ++i)
    c.keyframes[i] = KeyframePose{m.keyframe_utime[i], poseFromArray(m.odom_pose[i].data()),
                                  poseFromArray(m.map_pose[i].data())};
  for (std::int32_t i = 0; i < m.num_loops; ++i) c.loops.emplace_back(m.loop_from[std::size_t(i)], m.loop_to[std::size_t(i)]);
  out = std::move(c);
  return Validation::ok();
}

}  // namespace livo
