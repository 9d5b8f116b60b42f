#include "livo/io/map_messages.hpp"

#include "message_checks.hpp"

#include <algorithm>
#include <climits>
#include <stdexcept>
#include <string>

namespace livo {
namespace {

using namespace msgcheck;

constexpr int kPatchValues = PatchPyramid::kLevels * PatchPyramid::kCropValues;  // 432
constexpr int kMaxLayer = 3;  // plane_t.octant has 3 entries: layers 0..3

bool fitsInt32(std::int64_t v) { return v >= INT32_MIN && v <= INT32_MAX; }
/// Throws std::out_of_range naming `field` when a component of `k` does not fit the int32 of the message.
void checkKeyRange(const VoxelKey& k, const std::string& field) {
  if (!fitsInt32(k.x) || !fitsInt32(k.y) || !fitsInt32(k.z))
    throw std::out_of_range(field + ": voxel key (" + std::to_string(k.x) + ", " + std::to_string(k.y) + ", " +
                            std::to_string(k.z) + ") does not fit int32");
}

template <class T>
void upperFromMat3(const Mat3& c, T* u) {  // symmetric part as (xx, xy, xz, yy, yz, zz)
  u[0] = T(c(0, 0)); u[1] = T(0.5 * (c(0, 1) + c(1, 0))); u[2] = T(0.5 * (c(0, 2) + c(2, 0)));
  u[3] = T(c(1, 1)); u[4] = T(0.5 * (c(1, 2) + c(2, 1))); u[5] = T(c(2, 2));
}
template <class T>
Mat3 mat3FromUpper(const T* u) {
  Mat3 c;
  c << u[0], u[1], u[2], u[1], u[3], u[4], u[2], u[4], u[5];
  return c;
}

std::array<double, 7> joinPose(const double* position, const double* qxyzw) {
  return {position[0], position[1], position[2], qxyzw[0], qxyzw[1], qxyzw[2], qxyzw[3]};
}

// ---------- field checks, errors relative to the checked message ----------
Validation checkPatch(const livo::patch_t& m, const MessageLimits& lim) {
  LIVO_MSG_CHECK(utime(m.utime));
  if (m.levels != PatchPyramid::kLevels)
    return Validation::fail("levels: expected " + std::to_string(PatchPyramid::kLevels) +
                            " (PatchPyramid::kLevels), got " + std::to_string(m.levels));
  if (m.size != PatchPyramid::kCrop)
    return Validation::fail("size: expected " + std::to_string(PatchPyramid::kCrop) +
                            " (PatchPyramid::kCrop, the stored crop side), got " + std::to_string(m.size));
  LIVO_MSG_CHECK(count(m.num_values, lim.max_patch_values, "num_values", "max_patch_values"));
  if (m.num_values != kPatchValues)
    return Validation::fail("num_values: declares " + std::to_string(m.num_values) +
                            " but levels * size * size = " + std::to_string(kPatchValues));
  LIVO_MSG_CHECK(size(m.values, m.num_values, "values", "num_values"));
  LIVO_MSG_CHECK(finite(m.values.data(), m.num_values, "values"));
  for (std::size_t i = 0; i < m.values.size(); ++i)
    if (!PatchPyramid::isGrayValue(m.values[i]))
      return Validation::fail("values[" + std::to_string(i) + "]: expected a gray value in [0, 255], got " + num(m.values[i]));
  LIVO_MSG_CHECK(pose7(m.T_world_camera, "T_world_camera"));
  LIVO_MSG_CHECK(finite(m.pixel, 2, "pixel"));
  if (!std::isfinite(m.inv_exposure) || !(m.inv_exposure > 0.f))
    return Validation::fail("inv_exposure: expected a finite value > 0, got " + num(m.inv_exposure));
  return finite(&m.score, 1, "score");
}

Validation checkVisualPoint(const livo::visual_point_t& m, const MessageLimits& lim) {
  LIVO_MSG_CHECK(finite(m.position, 3, "position"));
  LIVO_MSG_CHECK(unitVector(m.normal, "normal"));
  LIVO_MSG_CHECK(covarianceUpper3(m.position_cov, "position_cov"));
  LIVO_MSG_CHECK(count(m.num_patches, lim.max_patches_per_point, "num_patches", "max_patches_per_point"));
  LIVO_MSG_CHECK(size(m.patches, m.num_patches, "patches", "num_patches"));
  if (m.bad_updates < 0) return Validation::fail("bad_updates: expected >= 0, got " + std::to_string(m.bad_updates));
  if (m.reference < -1 || m.reference >= m.num_patches)
    return Validation::fail("reference: index " + std::to_string(m.reference) + " outside -1.." +
                            std::to_string(m.num_patches - 1) + " (num_patches " + std::to_string(m.num_patches) + ")");
  if (m.views < m.num_patches)
    return Validation::fail("views: " + std::to_string(m.views) + " observations ever stored, fewer than num_patches " +
                            std::to_string(m.num_patches));
  for (std::int32_t i = 0; i < m.num_patches; ++i)
    LIVO_MSG_CHECK(nest(checkPatch(m.patches[std::size_t(i)], lim), "patches[" + std::to_string(i) + "]"));
  return Validation::ok();
}

Validation checkPlane(const livo::plane_t& m) {
  if (m.layer < 0 || m.layer > kMaxLayer)
    return Validation::fail("layer: " + std::to_string(m.layer) + " outside 0.." + std::to_string(kMaxLayer));
  for (int l = 0; l < 3; ++l) {
    const bool used = l < m.layer;
    if (used ? (m.octant[l] < 0 || m.octant[l] > 7) : m.octant[l] != -1)
      return Validation::fail("octant[" + std::to_string(l) + "]: " + std::to_string(m.octant[l]) + " but layer " +
                              std::to_string(m.layer) + (used ? " needs an octant 0..7 here" : " leaves it unused (-1)"));
  }
  LIVO_MSG_CHECK(finite(m.center, 3, "center"));
  LIVO_MSG_CHECK(unitVector(m.normal, "normal"));
  LIVO_MSG_CHECK(covariance(&m.covariance[0][0], 6, "covariance"));
  LIVO_MSG_CHECK(nonNegative(m.radius_m, "radius_m"));
  if (!std::isfinite(m.min_eigenvalue) || m.min_eigenvalue < -1e-6f)
    return Validation::fail("min_eigenvalue: expected a finite value >= 0, got " + num(m.min_eigenvalue));
  if (m.num_points < 0) return Validation::fail("num_points: negative count " + std::to_string(m.num_points));
  return Validation::ok();
}

Validation checkVisualPoints(const std::vector<livo::visual_point_t>& v, std::int32_t n, const char* field,
                             const MessageLimits& lim) {
  for (std::int32_t i = 0; i < n; ++i)
    LIVO_MSG_CHECK(nest(checkVisualPoint(v[std::size_t(i)], lim), field + ("[" + std::to_string(i) + "]")));
  return Validation::ok();
}

Validation checkQuery(const livo::map_query_t& m, const MessageLimits& lim) {
  LIVO_MSG_CHECK(utime(m.utime));
  LIVO_MSG_CHECK(finite(m.position, 3, "position"));
  LIVO_MSG_CHECK(quaternion(m.orientation, "orientation"));
  LIVO_MSG_CHECK(nonNegative(m.radius_m, "radius_m"));
  LIVO_MSG_CHECK(count(m.num_keys, lim.max_points, "num_keys", "max_points"));
  LIVO_MSG_CHECK(size(m.key_x, m.num_keys, "key_x", "num_keys"));
  LIVO_MSG_CHECK(size(m.key_y, m.num_keys, "key_y", "num_keys"));
  LIVO_MSG_CHECK(size(m.key_z, m.num_keys, "key_z", "num_keys"));
  LIVO_MSG_CHECK(count(m.num_visual_keys, lim.max_points, "num_visual_keys", "max_points"));
  LIVO_MSG_CHECK(size(m.visual_key_x, m.num_visual_keys, "visual_key_x", "num_visual_keys"));
  LIVO_MSG_CHECK(size(m.visual_key_y, m.num_visual_keys, "visual_key_y", "num_visual_keys"));
  LIVO_MSG_CHECK(size(m.visual_key_z, m.num_visual_keys, "visual_key_z", "num_visual_keys"));
  LIVO_MSG_CHECK(pose7(m.T_world_camera, "T_world_camera"));
  return nonNegative(m.max_visual_depth_m, "max_visual_depth_m");
}

Validation checkSubmap(const livo::submap_t& m, const MessageLimits& lim) {
  LIVO_MSG_CHECK(utime(m.utime));
  if (!std::isfinite(m.voxel_size_m) || !(m.voxel_size_m > 0.0))
    return Validation::fail("voxel_size_m: expected a finite value > 0, got " + num(m.voxel_size_m));
  LIVO_MSG_CHECK(count(m.num_planes, lim.max_planes, "num_planes", "max_planes"));
  LIVO_MSG_CHECK(size(m.planes, m.num_planes, "planes", "num_planes"));
  LIVO_MSG_CHECK(count(m.num_visual_points, lim.max_visual_points, "num_visual_points", "max_visual_points"));
  LIVO_MSG_CHECK(size(m.visual_points, m.num_visual_points, "visual_points", "num_visual_points"));
  if (m.next_visual_point_id < 1)
    return Validation::fail("next_visual_point_id: expected >= 1, got " + std::to_string(m.next_visual_point_id));
  for (std::int32_t i = 0; i < m.num_planes; ++i)
    LIVO_MSG_CHECK(nest(checkPlane(m.planes[std::size_t(i)]), "planes[" + std::to_string(i) + "]"));
  return checkVisualPoints(m.visual_points, m.num_visual_points, "visual_points", lim);
}

Validation checkUpdate(const livo::map_update_t& m, const MessageLimits& lim) {
  LIVO_MSG_CHECK(utime(m.utime));
  LIVO_MSG_CHECK(pose7(m.T_world_imu, "T_world_imu"));
  LIVO_MSG_CHECK(count(m.num_points, lim.max_points, "num_points", "max_points"));
  const std::int32_t n = m.num_points;
  LIVO_MSG_CHECK(size(m.x, n, "x", "num_points"));
  LIVO_MSG_CHECK(size(m.y, n, "y", "num_points"));
  LIVO_MSG_CHECK(size(m.z, n, "z", "num_points"));
  LIVO_MSG_CHECK(size(m.cov_xx, n, "cov_xx", "num_points"));
  LIVO_MSG_CHECK(size(m.cov_xy, n, "cov_xy", "num_points"));
  LIVO_MSG_CHECK(size(m.cov_xz, n, "cov_xz", "num_points"));
  LIVO_MSG_CHECK(size(m.cov_yy, n, "cov_yy", "num_points"));
  LIVO_MSG_CHECK(size(m.cov_yz, n, "cov_yz", "num_points"));
  LIVO_MSG_CHECK(size(m.cov_zz, n, "cov_zz", "num_points"));
  LIVO_MSG_CHECK(count(m.num_new_visual_points, lim.max_visual_points, "num_new_visual_points", "max_visual_points"));
  LIVO_MSG_CHECK(size(m.new_visual_points, m.num_new_visual_points, "new_visual_points", "num_new_visual_points"));
  LIVO_MSG_CHECK(count(m.num_observations, lim.max_visual_points, "num_observations", "max_visual_points"));
  LIVO_MSG_CHECK(size(m.observation_point_ids, m.num_observations, "observation_point_ids", "num_observations"));
  LIVO_MSG_CHECK(size(m.observations, m.num_observations, "observations", "num_observations"));
  for (std::int32_t i = 0; i < n; ++i) {
    const std::size_t k = std::size_t(i);
    const float* xyz[3] = {&m.x[k], &m.y[k], &m.z[k]};
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(*xyz[a]))
        return Validation::fail(std::string(1, char('x' + a)) + "[" + std::to_string(i) + "]: non-finite value " +
                                num(*xyz[a]));
    const float u[6] = {m.cov_xx[k], m.cov_xy[k], m.cov_xz[k], m.cov_yy[k], m.cov_yz[k], m.cov_zz[k]};
    Validation v = covarianceUpper3(u, "");  // error starts with ": ..."
    if (!v) return Validation::fail("cov_xx..cov_zz[" + std::to_string(i) + "]" + v.error);
  }
  LIVO_MSG_CHECK(checkVisualPoints(m.new_visual_points, m.num_new_visual_points, "new_visual_points", lim));
  for (std::int32_t i = 0; i < m.num_observations; ++i)
    LIVO_MSG_CHECK(nest(checkPatch(m.observations[std::size_t(i)], lim), "observations[" + std::to_string(i) + "]"));
  return Validation::ok();
}

Validation checkMapStats(const livo::map_stats_t& m) {
  LIVO_MSG_CHECK(utime(m.utime));
  const std::pair<std::int64_t, const char*> counts[] = {
      {m.local_voxels, "local_voxels"},
      {m.local_planes, "local_planes"},
      {m.visual_points_local, "visual_points_local"},
      {m.visual_points_longterm, "visual_points_longterm"},
      {m.bytes, "bytes"},
      {m.bytes_cap, "bytes_cap"},
      {m.evicted_visual_points, "evicted_visual_points"},
      {m.evicted_voxels, "evicted_voxels"},
      {m.slides, "slides"},
      {m.queries_answered, "queries_answered"}};
  for (const auto& c : counts)
    if (c.first < 0) return Validation::fail(std::string(c.second) + ": negative count " + std::to_string(c.first));
  return nonNegative(m.last_slide_ms, "last_slide_ms");
}

// ---------- conversions of validated messages ----------
void convert(const livo::patch_t& m, VisualObservation& o) {
  o.utime = m.utime;
  std::transform(m.values.begin(), m.values.end(), o.patch.values.begin(), PatchPyramid::quantize);
  o.T_world_camera = poseFromArray(m.T_world_camera);
  o.px = Vec2(m.pixel[0], m.pixel[1]);
  o.inv_exposure = m.inv_exposure;
  o.score = m.score;
}

void convert(const livo::visual_point_t& m, VisualPoint& p) {
  p = VisualPoint();
  p.id = m.id;
  p.p_world = Vec3(m.position[0], m.position[1], m.position[2]);
  p.normal = Vec3(m.normal[0], m.normal[1], m.normal[2]);
  p.cov = mat3FromUpper(m.position_cov);
  p.converged = m.converged != 0;
  p.bad_updates = m.bad_updates;
  p.reference = m.reference;
  p.views = m.views;
  p.from_longterm = m.from_longterm != 0;
  p.obs.resize(m.patches.size());
  for (std::size_t i = 0; i < m.patches.size(); ++i) convert(m.patches[i], p.obs[i]);
}

void convert(const livo::plane_t& m, SubmapPlane& s) {
  s = SubmapPlane();
  s.key = VoxelKey{m.voxel_key[0], m.voxel_key[1], m.voxel_key[2]};
  s.layer = m.layer;
  for (int l = 0; l < 3; ++l) s.octant[std::size_t(l)] = m.octant[l];
  s.frozen = m.frozen != 0;
  Plane& p = s.plane;
  p.center = Vec3(m.center[0], m.center[1], m.center[2]);
  p.normal = Vec3(m.normal[0], m.normal[1], m.normal[2]);
  p.d = -p.normal.dot(p.center);  // n^T p + d = 0 at the centre q
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) p.cov_nq(i, j) = m.covariance[i][j];
  p.radius = m.radius_m;
  p.eig_min = m.min_eigenvalue;
  p.eig_mid = 0.0;
  p.eig_max = p.radius * p.radius;  // radius = sqrt(lambda_max)
  p.num_points = m.num_points;
  p.layer = m.layer;
  p.is_plane = true;
}

void convertVisualPoints(const std::vector<livo::visual_point_t>& in, std::vector<VisualPoint>& out) {
  out.resize(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) convert(in[i], out[i]);
}

}  // namespace

// ---------------- patch_t / visual_point_t / plane_t ----------------
livo::patch_t toMsg(const VisualObservation& o) {
  livo::patch_t m{};
  m.utime = o.utime;
  m.levels = PatchPyramid::kLevels;
  m.size = PatchPyramid::kCrop;
  m.num_values = kPatchValues;
  m.values.assign(o.patch.values.begin(), o.patch.values.end());
  const auto T = poseToArray(o.T_world_camera);
  std::copy(T.begin(), T.end(), m.T_world_camera);
  m.pixel[0] = static_cast<float>(o.px.x());
  m.pixel[1] = static_cast<float>(o.px.y());
  m.inv_exposure = o.inv_exposure;
  m.score = o.score;
  return m;
}

livo::visual_point_t toMsg(const VisualPoint& p) {
  livo::visual_point_t m{};
  m.id = p.id;
  for (int i = 0; i < 3; ++i) {
    m.position[i] = p.p_world[i];
    m.normal[i] = p.normal[i];
  }
  upperFromMat3(p.cov, m.position_cov);
  m.converged = p.converged;
  m.bad_updates = p.bad_updates;
  m.reference = p.reference;
  m.views = p.viewCount();
  m.from_longterm = p.from_longterm;
  m.num_patches = static_cast<std::int32_t>(p.obs.size());
  m.patches.reserve(p.obs.size());
  for (const auto& o : p.obs) m.patches.push_back(toMsg(o));
  return m;
}

livo::plane_t toMsg(const SubmapPlane& s) {
  livo::plane_t m{};
  checkKeyRange(s.key, "plane_t.voxel_key");
  m.voxel_key[0] = static_cast<std::int32_t>(s.key.x);
  m.voxel_key[1] = static_cast<std::int32_t>(s.key.y);
  m.voxel_key[2] = static_cast<std::int32_t>(s.key.z);
  m.layer = static_cast<std::int8_t>(s.layer);
  for (int l = 0; l < 3; ++l) m.octant[l] = s.octant[std::size_t(l)];
  for (int i = 0; i < 3; ++i) {
    m.center[i] = s.plane.center[i];
    m.normal[i] = s.plane.normal[i];
  }
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) m.covariance[i][j] = s.plane.cov_nq(i, j);
  m.radius_m = static_cast<float>(s.plane.radius);
  m.min_eigenvalue = static_cast<float>(s.plane.eig_min);
  m.num_points = s.plane.num_points;
  m.frozen = s.frozen;
  return m;
}

Validation validate(const livo::patch_t& m, const MessageLimits& lim) { return nest(checkPatch(m, lim), "patch_t"); }
Validation validate(const livo::visual_point_t& m, const MessageLimits& lim) {
  return nest(checkVisualPoint(m, lim), "visual_point_t");
}
Validation validate(const livo::plane_t& m, const MessageLimits&) { return nest(checkPlane(m), "plane_t"); }

Validation fromMsg(const livo::patch_t& m, VisualObservation& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  convert(m, out);
  return Validation::ok();
}
Validation fromMsg(const livo::visual_point_t& m, VisualPoint& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  convert(m, out);
  return Validation::ok();
}
Validation fromMsg(const livo::plane_t& m, SubmapPlane& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  convert(m, out);
  return Validation::ok();
}

// ---------------- map_query_t ----------------
livo::map_query_t toMsg(const MapQuery& q) {
  livo::map_query_t m{};
  m.utime = q.utime;
  m.request_id = q.request_id;
  const auto T = poseToArray(q.T_world_imu);
  std::copy(T.begin(), T.begin() + 3, m.position);
  std::copy(T.begin() + 3, T.end(), m.orientation);
  m.radius_m = q.radius_m;
  const std::size_t n = q.keys.size();
  m.num_keys = static_cast<std::int32_t>(n);
  m.key_x.resize(n); m.key_y.resize(n); m.key_z.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const VoxelKey& k = q.keys[i];
    if (!fitsInt32(k.x) || !fitsInt32(k.y) || !fitsInt32(k.z))
      checkKeyRange(k, "map_query_t.keys[" + std::to_string(i) + "]");  // throws
    m.key_x[i] = static_cast<std::int32_t>(k.x);
    m.key_y[i] = static_cast<std::int32_t>(k.y);
    m.key_z[i] = static_cast<std::int32_t>(k.z);
  }
  const std::size_t nv = q.visual_keys.size();
  m.num_visual_keys = static_cast<std::int32_t>(nv);
  m.visual_key_x.resize(nv); m.visual_key_y.resize(nv); m.visual_key_z.resize(nv);
  for (std::size_t i = 0; i < nv; ++i) {
    const VoxelKey& k = q.visual_keys[i];
    if (!fitsInt32(k.x) || !fitsInt32(k.y) || !fitsInt32(k.z))
      checkKeyRange(k, "map_query_t.visual_keys[" + std::to_string(i) + "]");  // throws
    m.visual_key_x[i] = static_cast<std::int32_t>(k.x);
    m.visual_key_y[i] = static_cast<std::int32_t>(k.y);
    m.visual_key_z[i] = static_cast<std::int32_t>(k.z);
  }
  m.want_visual = q.want_visual;
  const auto C = poseToArray(q.T_world_camera);
  std::copy(C.begin(), C.end(), m.T_world_camera);
  m.max_visual_depth_m = q.max_visual_depth_m;
  return m;
}

Validation validate(const livo::map_query_t& m, const MessageLimits& lim) {
  return nest(checkQuery(m, lim), "map_query_t");
}

Validation fromMsg(const livo::map_query_t& m, MapQuery& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  out.utime = m.utime;
  out.request_id = m.request_id;
  out.T_world_imu = poseFromArray(joinPose(m.position, m.orientation).data());
  out.radius_m = m.radius_m;
  out.keys.resize(std::size_t(m.num_keys));
  for (std::size_t i = 0; i < out.keys.size(); ++i) out.keys[i] = VoxelKey{m.key_x[i], m.key_y[i], m.key_z[i]};
  out.visual_keys.resize(std::size_t(m.num_visual_keys));
  for (std::size_t i = 0; i < out.visual_keys.size(); ++i)
    out.visual_keys[i] = VoxelKey{m.visual_key_x[i], m.visual_key_y[i], m.visual_key_z[i]};
  out.want_visual = m.want_visual != 0;
  out.T_world_camera = poseFromArray(m.T_world_camera);
  out.max_visual_depth_m = m.max_visual_depth_m;
  return Validation::ok();
}

// ---------------- submap_t ----------------
livo::submap_t toMsg(const Submap& s) {
  livo::submap_t m{};
  m.utime = s.utime;
  m.request_id = s.request_id;
  m.voxel_size_m = s.voxel_size_m;
  m.num_planes = static_cast<std::int32_t>(s.planes.size());
  m.planes.reserve(s.planes.size());
  for (std::size_t i = 0; i < s.planes.size(); ++i) {
    try {
      m.planes.push_back(toMsg(s.planes[i]));
    } catch (const std::out_of_range& e) {  // name the element
      throw std::out_of_range("submap_t.planes[" + std::to_string(i) + "]: " + e.what());
    }
  }
  m.next_visual_point_id = s.next_visual_point_id;
  m.num_visual_points = static_cast<std::int32_t>(s.visual_points.size());
  m.visual_points.reserve(s.visual_points.size());
  for (const auto& p : s.visual_points) m.visual_points.push_back(toMsg(p));
  return m;
}

Validation validate(const livo::submap_t& m, const MessageLimits& lim) { return nest(checkSubmap(m, lim), "submap_t"); }

Validation fromMsg(const livo::submap_t& m, Submap& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  out.utime = m.utime;
  out.request_id = m.request_id;
  out.voxel_size_m = m.voxel_size_m;
  out.planes.resize(m.planes.size());
  for (std::size_t i = 0; i < m.planes.size(); ++i) convert(m.planes[i], out.planes[i]);
  convertVisualPoints(m.visual_points, out.visual_points);
  out.next_visual_point_id = m.next_visual_point_id;
  return Validation::ok();
}

// ---------------- map_update_t ----------------
livo::map_update_t toMsg(const MapUpdate& u) {
  livo::map_update_t m{};
  m.utime = u.utime;
  m.request_id = u.request_id;
  const auto T = poseToArray(u.T_world_imu);
  std::copy(T.begin(), T.end(), m.T_world_imu);
  const std::size_t n = u.points.size();
  m.num_points = static_cast<std::int32_t>(n);
  for (auto* v : {&m.x, &m.y, &m.z, &m.cov_xx, &m.cov_xy, &m.cov_xz, &m.cov_yy, &m.cov_yz, &m.cov_zz}) v->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const PointWithCov& p = u.points[i];
    m.x[i] = float(p.p_world.x()); m.y[i] = float(p.p_world.y()); m.z[i] = float(p.p_world.z());
    float c[6];
    upperFromMat3(p.cov_world, c);
    m.cov_xx[i] = c[0]; m.cov_xy[i] = c[1]; m.cov_xz[i] = c[2];
    m.cov_yy[i] = c[3]; m.cov_yz[i] = c[4]; m.cov_zz[i] = c[5];
  }
  m.num_new_visual_points = static_cast<std::int32_t>(u.new_visual_points.size());
  m.new_visual_points.reserve(u.new_visual_points.size());
  for (const auto& p : u.new_visual_points) m.new_visual_points.push_back(toMsg(p));
  m.num_observations = static_cast<std::int32_t>(u.observations.size());
  m.observation_point_ids.reserve(u.observations.size());
  m.observations.reserve(u.observations.size());
  for (const auto& [id, obs] : u.observations) {
    m.observation_point_ids.push_back(id);
    m.observations.push_back(toMsg(obs));
  }
  return m;
}

Validation validate(const livo::map_update_t& m, const MessageLimits& lim) {
  return nest(checkUpdate(m, lim), "map_update_t");
}

Validation fromMsg(const livo::map_update_t& m, MapUpdate& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  out.utime = m.utime;
  out.request_id = m.request_id;
  out.T_world_imu = poseFromArray(m.T_world_imu);
  out.points.resize(std::size_t(m.num_points));
  for (std::size_t i = 0; i < out.points.size(); ++i) {
    out.points[i].p_world = Vec3(m.x[i], m.y[i], m.z[i]);
    const float u[6] = {m.cov_xx[i], m.cov_xy[i], m.cov_xz[i], m.cov_yy[i], m.cov_yz[i], m.cov_zz[i]};
    out.points[i].cov_world = mat3FromUpper(u);
  }
  convertVisualPoints(m.new_visual_points, out.new_visual_points);
  out.observations.resize(std::size_t(m.num_observations));
  for (std::size_t i = 0; i < out.observations.size(); ++i) {
    out.observations[i].first = m.observation_point_ids[i];
    convert(m.observations[i], out.observations[i].second);
  }
  return Validation::ok();
}

// ---------------- map_stats_t ----------------
livo::map_stats_t toMsg(const MapStats& s) {
  livo::map_stats_t m{};
  m.utime = s.utime;
  m.local_voxels = s.local_voxels;
  m.local_planes = s.local_planes;
  m.visual_points_local = s.visual_points_local;
  m.visual_points_longterm = s.visual_points_longterm;
  m.bytes = s.bytes;
  m.bytes_cap = s.bytes_cap;
  m.evicted_visual_points = s.evicted_visual_points;
  m.evicted_voxels = s.evicted_voxels;
  m.slides = s.slides;
  m.queries_answered = s.queries_answered;
  m.last_slide_ms = s.last_slide_ms;
  return m;
}

Validation validate(const livo::map_stats_t& m, const MessageLimits&) { return nest(checkMapStats(m), "map_stats_t"); }

Validation fromMsg(const livo::map_stats_t& m, MapStats& out, const MessageLimits& lim) {
  LIVO_MSG_CHECK(validate(m, lim));
  out.utime = m.utime;
  out.local_voxels = m.local_voxels;
  out.local_planes = m.local_planes;
  out.visual_points_local = m.visual_points_local;
  out.visual_points_longterm = m.visual_points_longterm;
  out.bytes = m.bytes;
  out.bytes_cap = m.bytes_cap;
  out.evicted_visual_points = m.evicted_visual_points;
  out.evicted_voxels = m.evicted_voxels;
  out.slides = m.slides;
  out.queries_answered = m.queries_answered;
  out.last_slide_ms = m.last_slide_ms;
  return Validation::ok();
}

}  // namespace livo
