// Walks the raw LCM encoding of every livo message without allocating, checking each declared count
// against the bytes that remain and against MessageLimits. Only after this passes does decode() let the
// generated code resize vectors from those counts. The field order here mirrors lcmtypes/*.lcm.
#include "livo/io/convert.hpp"

#include <livo/estimator_stats_t.hpp>
#include <livo/filter_state_t.hpp>
#include <livo/map_correction_t.hpp>
#include <livo/map_query_t.hpp>
#include <livo/map_stats_t.hpp>
#include <livo/map_update_t.hpp>
#include <livo/odometry_t.hpp>
#include <livo/patch_t.hpp>
#include <livo/plane_t.hpp>
#include <livo/registered_scan_t.hpp>
#include <livo/resume_request_t.hpp>
#include <livo/resume_t.hpp>
#include <livo/submap_t.hpp>
#include <livo/visual_point_t.hpp>

namespace livo {
namespace {

/// Cursor over big-endian LCM bytes that records the first error with the field's dotted name.
class Walker {
 public:
  Walker(const std::uint8_t* p, std::size_t n, const MessageLimits& lim) : p_(p), n_(n), lim_(lim) {}

  bool skip(std::size_t bytes, const std::string& field) {
    if (!err_.empty()) return false;
    if (bytes > n_ - pos_) return fail(field + ": message ends early (needs " + std::to_string(bytes) + " bytes, " +
                                       std::to_string(n_ - pos_) + " left)");
    pos_ += bytes;
    return true;
  }
  /// Reads an int32 count, checks 0 <= count <= max and that count * min_elem_bytes fits in what remains.
  bool count(const std::string& field, std::int64_t max, std::size_t min_elem_bytes, std::int32_t& out) {
    if (!err_.empty()) return false;
    if (n_ - pos_ < 4) return fail(field + ": message ends early");
    const std::uint32_t u = (std::uint32_t(p_[pos_]) << 24) | (std::uint32_t(p_[pos_ + 1]) << 16) |
                            (std::uint32_t(p_[pos_ + 2]) << 8) | std::uint32_t(p_[pos_ + 3]);
    out = static_cast<std::int32_t>(u);
    pos_ += 4;
    if (out < 0) return fail(field + ": negative count " + std::to_string(out));
    if (out > max) return fail(field + ": count " + std::to_string(out) + " exceeds the limit " + std::to_string(max));
    if (static_cast<std::uint64_t>(out) * min_elem_bytes > n_ - pos_)
      return fail(field + ": declared " + std::to_string(out) + " elements but only " + std::to_string(n_ - pos_) +
                  " bytes remain");
    return true;
  }
  bool string(const std::string& field) {
    std::int32_t len = 0;
    if (!count(field, 1 << 20, 1, len)) return false;
    if (len == 0) return fail(field + ": string length 0 (must include the terminating NUL)");
    // LCM's C++ code encodes a string up to its first NUL but sizes the message by its length: a NUL
    // inside would decode, then re-encode into a shorter message than it says (found by the fuzz test's
    // run under qemu on arm64).
    const std::size_t n = static_cast<std::size_t>(len);
    if (n <= n_ - pos_) {
      const void* nul = std::memchr(p_ + pos_, 0, n);
      if (nul == nullptr) return fail(field + ": string without its terminating NUL");
      if (static_cast<const std::uint8_t*>(nul) != p_ + pos_ + n - 1)
        return fail(field + ": string holds a NUL byte at " +
                    std::to_string(static_cast<const std::uint8_t*>(nul) - (p_ + pos_)) + " of " +
                    std::to_string(n - 1));
    }
    return skip(n, field);
  }
  bool fail(std::string e) {
    if (err_.empty()) err_ = std::move(e);
    return false;
  }
  bool finish(const std::string& type) {
    if (!err_.empty()) return false;
    if (pos_ != n_) return fail(type + ": " + std::to_string(n_ - pos_) + " trailing bytes after the message");
    return true;
  }
  const MessageLimits& lim() const { return lim_; }
  const std::string& error() const { return err_; }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
  const MessageLimits& lim_;
  std::string err_;
};

// Fixed-size types: their encoded size without hash is that of a default instance.
template <class Msg>
std::size_t fixedSize() {
  static const std::size_t n = static_cast<std::size_t>(Msg()._getEncodedSizeNoHash());
  return n;
}

bool walkImu(Walker& w, const std::string& f) { return w.skip(fixedSize<livo::imu_t>(), f); }

bool walkLidar(Walker& w, const std::string& f) {
  std::int32_t n = 0;
  // utime; num_points; x, y, z, time_offset_s, intensity (float); ring (int16); sensor (string)
  return w.skip(8, f + ".utime") && w.count(f + ".num_points", w.lim().max_points, 4 * 5 + 2, n) &&
         w.skip(std::size_t(n) * (4 * 5 + 2), f + ".x..ring") && w.string(f + ".sensor");
}

bool walkImage(Walker& w, const std::string& f) {
  std::int32_t n = 0;
  // utime, width, height, row_stride, pixel_format, exposure_time_s; size; data
  return w.skip(8 + 4 + 4 + 4 + 1 + 4, f + ".header") &&
         w.count(f + ".size", w.lim().max_message_bytes, 1, n) && w.skip(std::size_t(n), f + ".data");
}

bool walkFrame(Walker& w, const std::string& f) {
  std::int32_t n = 0;
  if (!(w.skip(16, f + ".utime") && w.count(f + ".num_imu", w.lim().max_imu_per_frame, fixedSize<livo::imu_t>(), n)))
    return false;
  return w.skip(std::size_t(n) * fixedSize<livo::imu_t>(), f + ".imu") && walkLidar(w, f + ".sweep") &&
         w.skip(1, f + ".has_image") && walkImage(w, f + ".image");
}

bool walkPatch(Walker& w, const std::string& f) {
  std::int32_t n = 0;
  // utime, levels, size; num_values; values; T_world_camera[7], pixel[2], inv_exposure, score
  return w.skip(8 + 1 + 1, f + ".header") && w.count(f + ".num_values", w.lim().max_patch_values, 4, n) &&
         w.skip(std::size_t(n) * 4, f + ".values") && w.skip(56 + 8 + 4 + 4, f + ".pose");
}

bool walkVisualPoint(Walker& w, const std::string& f) {
  std::int32_t n = 0;
  // id, position[3], normal[3], position_cov[6] (float), converged, bad_updates, reference, views,
  // from_longterm; num_patches; patches
  if (!(w.skip(8 + 24 + 24 + 24 + 1 + 4 + 4 + 4 + 1, f + ".header") &&
        w.count(f + ".num_patches", w.lim().max_patches_per_point, 8 + 2 + 4 + 72, n)))
    return false;
  for (std::int32_t i = 0; i < n; ++i)
    if (!walkPatch(w, f + ".patches[" + std::to_string(i) + "]")) return false;
  return true;
}

bool walkQuery(Walker& w, const std::string& f) {
  std::int32_t n = 0, nv = 0;
  // utime, request_id, position[3], orientation[4], radius_m; num_keys; key_x/y/z; num_visual_keys;
  // visual_key_x/y/z; want_visual, T[7], depth
  return w.skip(8 + 8 + 24 + 32 + 8, f + ".header") && w.count(f + ".num_keys", w.lim().max_points, 12, n) &&
         w.skip(std::size_t(n) * 12, f + ".key_xyz") &&
         w.count(f + ".num_visual_keys", w.lim().max_points, 12, nv) &&
         w.skip(std::size_t(nv) * 12, f + ".visual_key_xyz") && w.skip(1 + 56 + 8, f + ".camera");
}

bool walkSubmap(Walker& w, const std::string& f) {
  std::int32_t np = 0, nv = 0;
  const std::size_t plane = fixedSize<livo::plane_t>();
  if (!(w.skip(24, f + ".header") && w.count(f + ".num_planes", w.lim().max_planes, plane, np) &&
        w.skip(std::size_t(np) * plane, f + ".planes") && w.skip(8, f + ".next_visual_point_id") &&
        w.count(f + ".num_visual_points", w.lim().max_visual_points, 89 + 4, nv)))
    return false;
  for (std::int32_t i = 0; i < nv; ++i)
    if (!walkVisualPoint(w, f + ".visual_points[" + std::to_string(i) + "]")) return false;
  return true;
}

bool walkUpdate(Walker& w, const std::string& f) {
  std::int32_t np = 0, nv = 0, no = 0;
  if (!(w.skip(8 + 8 + 56, f + ".header") && w.count(f + ".num_points", w.lim().max_points, 36, np) &&
        w.skip(std::size_t(np) * 36, f + ".points") &&
        w.count(f + ".num_new_visual_points", w.lim().max_visual_points, 89 + 4, nv)))
    return false;
  for (std::int32_t i = 0; i < nv; ++i)
    if (!walkVisualPoint(w, f + ".new_visual_points[" + std::to_string(i) + "]")) return false;
  if (!(w.count(f + ".num_observations", w.lim().max_visual_points, 8 + 10 + 4 + 72, no) &&
        w.skip(std::size_t(no) * 8, f + ".observation_point_ids")))
    return false;
  for (std::int32_t i = 0; i < no; ++i)
    if (!walkPatch(w, f + ".observations[" + std::to_string(i) + "]")) return false;
  return true;
}

bool walkRegistered(Walker& w, const std::string& f) {
  std::int32_t n = 0, nc = 0;
  return w.skip(8, f + ".utime") && w.count(f + ".num_points", w.lim().max_points, 16, n) &&
         w.skip(std::size_t(n) * 16, f + ".xyzi") && w.count(f + ".num_colors", w.lim().max_points, 4, nc) &&
         w.skip(std::size_t(nc) * 4, f + ".rgb");
}

bool walkOdometry(Walker& w, const std::string& f) { return w.skip(fixedSize<livo::odometry_t>(), f); }
bool walkEstStats(Walker& w, const std::string& f) {
  // Every field has a fixed size but the last, health_reason (a string: 4 + 1 bytes when empty).
  return w.skip(fixedSize<livo::estimator_stats_t>() - 5, f) && w.string(f + ".health_reason");
}
bool walkMapStats(Walker& w, const std::string& f) { return w.skip(fixedSize<livo::map_stats_t>(), f); }
bool walkPlane(Walker& w, const std::string& f) { return w.skip(fixedSize<livo::plane_t>(), f); }
bool walkFilterState(Walker& w, const std::string& f) { return w.skip(fixedSize<livo::filter_state_t>(), f); }
bool walkResumeRequest(Walker& w, const std::string& f) {
  return w.skip(8, f + ".request_id") && w.string(f + ".config");
}

bool walkResume(Walker& w, const std::string& f) {
  std::int32_t n = 0;
  const std::size_t imu = fixedSize<livo::imu_t>();
  // request_id, have_state, state; num_imu; imu; imu_dropped
  return w.skip(8 + 1, f + ".header") && w.skip(fixedSize<livo::filter_state_t>(), f + ".state") &&
         w.count(f + ".num_imu", w.lim().max_imu_per_frame, imu, n) && w.skip(std::size_t(n) * imu, f + ".imu") &&
         w.skip(8, f + ".imu_dropped") && w.string(f + ".config_mismatch");
}

bool walkCorrection(Walker& w, const std::string& f) {
  std::int32_t n = 0, nl = 0;
  // utime, position[3], orientation[4], keyframes_total, solves, final, first_keyframe; num_keyframes;
  // keyframe_utime, odom_pose[7], map_pose[7]; num_loops; loop_from, loop_to
  constexpr std::size_t kKeyframe = 8 + 56 + 56;
  return w.skip(8 + 24 + 32 + 4 + 4 + 1 + 4, f + ".header") &&
         w.count(f + ".num_keyframes", w.lim().max_keyframes, kKeyframe, n) &&
         w.skip(std::size_t(n) * kKeyframe, f + ".keyframes") && w.count(f + ".num_loops", w.lim().max_keyframes, 8, nl) &&
         w.skip(std::size_t(nl) * 8, f + ".loops");
}

template <class Msg, class WalkFn>
Validation run(const void* data, std::size_t size, const MessageLimits& lim, WalkFn walk) {
  const std::string type = Msg::getTypeName();
  if (data == nullptr && size > 0) return Validation::fail(type + ": null buffer");
  if (static_cast<std::int64_t>(size) > lim.max_message_bytes)
    return Validation::fail(type + ": message of " + std::to_string(size) + " bytes exceeds max_message_bytes " +
                            std::to_string(lim.max_message_bytes));
  if (size < 8) return Validation::fail(type + ": message of " + std::to_string(size) + " bytes is too short");
  const auto* p = static_cast<const std::uint8_t*>(data);
  std::uint64_t hash = 0;
  for (int i = 0; i < 8; ++i) hash = (hash << 8) | p[i];
  if (static_cast<std::int64_t>(hash) != Msg::getHash())
    return Validation::fail(type + ": fingerprint mismatch (not a " + type + " or a different version)");
  Walker w(p + 8, size - 8, lim);
  if (!walk(w, type) || !w.finish(type)) return Validation::fail(w.error());
  return Validation::ok();
}

}  // namespace

#define LIVO_PRECHECK(MSG, WALK)                                                               \
  template <>                                                                                  \
  Validation precheck<MSG>(const void* data, std::size_t size, const MessageLimits& lim) {     \
    return run<MSG>(data, size, lim, [](Walker& w, const std::string& f) { return WALK(w, f); }); \
  }

LIVO_PRECHECK(livo::imu_t, walkImu)
LIVO_PRECHECK(livo::lidar_scan_t, walkLidar)
LIVO_PRECHECK(livo::image_t, walkImage)
LIVO_PRECHECK(livo::frame_t, walkFrame)
LIVO_PRECHECK(livo::map_query_t, walkQuery)
LIVO_PRECHECK(livo::plane_t, walkPlane)
LIVO_PRECHECK(livo::patch_t, walkPatch)
LIVO_PRECHECK(livo::visual_point_t, walkVisualPoint)
LIVO_PRECHECK(livo::submap_t, walkSubmap)
LIVO_PRECHECK(livo::map_update_t, walkUpdate)
LIVO_PRECHECK(livo::odometry_t, walkOdometry)
LIVO_PRECHECK(livo::registered_scan_t, walkRegistered)
LIVO_PRECHECK(livo::estimator_stats_t, walkEstStats)
LIVO_PRECHECK(livo::map_stats_t, walkMapStats)
LIVO_PRECHECK(livo::filter_state_t, walkFilterState)
LIVO_PRECHECK(livo::resume_request_t, walkResumeRequest)
LIVO_PRECHECK(livo::resume_t, walkResume)
LIVO_PRECHECK(livo::map_correction_t, walkCorrection)
#undef LIVO_PRECHECK

}  // namespace livo
