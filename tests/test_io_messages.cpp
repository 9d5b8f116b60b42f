// libs/io map and estimator messages: struct -> message -> bytes -> decode -> struct round trips with
// random values (fixed seed) for every type, validation errors that name the field for each class of
// error, toMsg range errors, and the encoded size of a large submap (per plane, per visual point).
#include "livo/io/estimator_messages.hpp"
#include "livo/io/map_messages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>

using namespace livo;

namespace {

std::mt19937 rng(20240611);
double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
std::int64_t uniInt(std::int64_t a, std::int64_t b) { return std::uniform_int_distribution<std::int64_t>(a, b)(rng); }
Vec3 randVec3(double s) { return Vec3(uni(-s, s), uni(-s, s), uni(-s, s)); }
Vec3 randUnit() { return randVec3(1.0).normalized(); }
Pose randPose() {
  Pose T = Pose::Identity();
  T.linear() = expSO3(randVec3(3.0));
  T.translation() = randVec3(500.0);
  return T;
}
template <int N>
Eigen::Matrix<double, N, N> randCov(double s) {  // A A^T: symmetric PSD
  const Eigen::Matrix<double, N, N> A = Eigen::Matrix<double, N, N>::NullaryExpr([] { return uni(-1, 1); }) * s;
  return A * A.transpose();
}

VisualObservation randObs() {
  VisualObservation o;
  o.utime = uniInt(0, 1'800'000'000'000'000);
  for (auto& v : o.patch.values) v = static_cast<std::uint8_t>(uniInt(0, 255));
  o.T_world_camera = randPose();
  o.px = Vec2(uni(0, 1280), uni(0, 1024));
  o.inv_exposure = static_cast<float>(uni(0.2, 5));
  o.score = static_cast<float>(uni(-1, 2));
  return o;
}
VisualPoint randVisualPoint(int n_obs) {
  VisualPoint p;
  p.id = uniInt(0, std::numeric_limits<std::int64_t>::max());
  p.p_world = randVec3(500);
  p.normal = randUnit();
  p.cov = randCov<3>(0.05);
  for (int i = 0; i < n_obs; ++i) p.obs.push_back(randObs());
  p.reference = n_obs > 0 ? int(uniInt(-1, n_obs - 1)) : -1;
  p.converged = uniInt(0, 1) == 1;
  p.bad_updates = uniInt(0, 5);
  p.views = n_obs + std::int32_t(uniInt(0, 9));
  p.from_longterm = uniInt(0, 1) == 1;
  return p;
}
SubmapPlane randPlane() {
  SubmapPlane s;
  s.key = VoxelKey{uniInt(-100000, 100000), uniInt(-100000, 100000), uniInt(-1000, 1000)};
  s.layer = int(uniInt(0, 3));
  for (int l = 0; l < s.layer; ++l) s.octant[std::size_t(l)] = std::int8_t(uniInt(0, 7));
  s.frozen = uniInt(0, 1) == 1;
  Plane& p = s.plane;
  p.center = randVec3(500);
  p.normal = randUnit();
  p.d = -p.normal.dot(p.center);
  p.cov_nq = randCov<6>(0.01);
  p.radius = double(float(uni(0.01, 0.5)));  // float fields chosen representable: exact round trip
  p.eig_min = double(float(uni(0, 0.002)));
  p.eig_mid = 0.0;
  p.eig_max = p.radius * p.radius;
  p.num_points = int(uniInt(5, 50));
  p.layer = s.layer;
  p.is_plane = true;
  return s;
}

/// toMsg -> encode -> decode (precheck + generated code) -> fromMsg.
template <class Msg, class T>
T roundTrip(const T& in, std::size_t* bytes = nullptr) {
  const Msg m = toMsg(in);
  const auto buf = encode(m);
  if (bytes) *bytes = buf.size();
  Msg back{};
  const Validation d = decode(buf.data(), buf.size(), back);
  EXPECT_TRUE(d) << d.error;
  T out{};
  const Validation v = fromMsg(back, out);
  EXPECT_TRUE(v) << v.error;
  return out;
}

void expectPoseNear(const Pose& a, const Pose& b) {
  EXPECT_TRUE(a.translation() == b.translation());  // exact: doubles
  EXPECT_LT((a.linear() - b.linear()).cwiseAbs().maxCoeff(), 1e-14);  // through a quaternion
}
double f32(double v) { return double(float(v)); }
void expectObsEq(const VisualObservation& a, const VisualObservation& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_TRUE(a.patch.values == b.patch.values);
  expectPoseNear(a.T_world_camera, b.T_world_camera);
  EXPECT_EQ(f32(a.px.x()), b.px.x());
  EXPECT_EQ(f32(a.px.y()), b.px.y());
  EXPECT_EQ(a.inv_exposure, b.inv_exposure);
  EXPECT_EQ(a.score, b.score);
}
void expectCov3AtFloat(const Mat3& a, const Mat3& b) {  // symmetric part, float precision
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(f32(i == j ? a(i, i) : 0.5 * (a(i, j) + a(j, i))), b(i, j));
}
void expectVisualPointEq(const VisualPoint& a, const VisualPoint& b) {
  EXPECT_EQ(a.id, b.id);
  EXPECT_TRUE(a.p_world == b.p_world);
  EXPECT_TRUE(a.normal == b.normal);
  expectCov3AtFloat(a.cov, b.cov);
  EXPECT_EQ(a.reference, b.reference);
  EXPECT_EQ(a.converged, b.converged);
  EXPECT_EQ(a.bad_updates, b.bad_updates);
  EXPECT_EQ(a.views, b.views);
  EXPECT_EQ(a.from_longterm, b.from_longterm);
  ASSERT_EQ(a.obs.size(), b.obs.size());
  for (std::size_t i = 0; i < a.obs.size(); ++i) expectObsEq(a.obs[i], b.obs[i]);
}
void expectPlaneEq(const SubmapPlane& a, const SubmapPlane& b) {
  EXPECT_EQ(a.key, b.key);
  EXPECT_EQ(a.layer, b.layer);
  EXPECT_EQ(a.octant, b.octant);
  EXPECT_EQ(a.frozen, b.frozen);
  EXPECT_TRUE(a.plane.center == b.plane.center);
  EXPECT_TRUE(a.plane.normal == b.plane.normal);
  EXPECT_EQ(a.plane.d, b.plane.d);
  EXPECT_TRUE(a.plane.cov_nq == b.plane.cov_nq);
  EXPECT_EQ(a.plane.radius, b.plane.radius);
  EXPECT_EQ(a.plane.eig_min, b.plane.eig_min);
  EXPECT_EQ(a.plane.eig_max, b.plane.eig_max);
  EXPECT_EQ(a.plane.num_points, b.plane.num_points);
  EXPECT_EQ(a.plane.layer, b.plane.layer);
  EXPECT_TRUE(b.plane.is_plane);
}

Submap randSubmap(int planes, int points, int obs) {
  Submap s;
  s.utime = 1'700'000'000'000'000;
  s.request_id = 42;
  s.voxel_size_m = 0.5;
  s.next_visual_point_id = 1000 + points;
  for (int i = 0; i < planes; ++i) s.planes.push_back(randPlane());
  for (int i = 0; i < points; ++i) s.visual_points.push_back(randVisualPoint(obs));
  return s;
}

/// The error must start with `prefix` (the dotted field path) and contain `detail`.
void expectError(const Validation& v, const std::string& prefix, const std::string& detail = "") {
  ASSERT_FALSE(v) << "expected an error at " << prefix;
  EXPECT_EQ(v.error.rfind(prefix, 0), 0u) << v.error;
  EXPECT_NE(v.error.find(detail), std::string::npos) << v.error;
}

}  // namespace

TEST(MapMessages, RoundTripPatchVisualPointAndPlane) {
  for (int k = 0; k < 20; ++k) {
    const VisualObservation o = randObs();
    expectObsEq(o, roundTrip<livo::patch_t>(o));
    const VisualPoint p = randVisualPoint(k % 5);
    expectVisualPointEq(p, roundTrip<livo::visual_point_t>(p));
    const SubmapPlane s = randPlane();
    expectPlaneEq(s, roundTrip<livo::plane_t>(s));
  }
  EXPECT_EQ(toMsg(randObs()).size, PatchPyramid::kCrop);
  EXPECT_EQ(toMsg(randObs()).num_values, 432);
}

TEST(MapMessages, RoundTripQuerySubmapUpdateStats) {
  MapQuery q;
  q.utime = 123456789;
  q.request_id = 9;
  q.T_world_imu = randPose();
  q.radius_m = 40;
  for (int i = 0; i < 50; ++i) q.keys.push_back({uniInt(INT32_MIN, INT32_MAX), uniInt(-9, 9), uniInt(INT32_MIN, INT32_MAX)});
  for (int i = 0; i < 20; ++i) q.visual_keys.push_back({uniInt(-9, 9), uniInt(INT32_MIN, INT32_MAX), uniInt(-9, 9)});
  q.want_visual = true;
  q.T_world_camera = randPose();
  q.max_visual_depth_m = 25;
  const MapQuery qb = roundTrip<livo::map_query_t>(q);
  EXPECT_EQ(qb.utime, q.utime);
  EXPECT_EQ(qb.request_id, q.request_id);
  expectPoseNear(q.T_world_imu, qb.T_world_imu);
  EXPECT_EQ(qb.radius_m, q.radius_m);
  ASSERT_EQ(qb.keys.size(), q.keys.size());
  for (std::size_t i = 0; i < q.keys.size(); ++i) EXPECT_EQ(qb.keys[i], q.keys[i]);
  ASSERT_EQ(qb.visual_keys.size(), q.visual_keys.size());
  for (std::size_t i = 0; i < q.visual_keys.size(); ++i) EXPECT_EQ(qb.visual_keys[i], q.visual_keys[i]);
  EXPECT_TRUE(qb.want_visual);
  expectPoseNear(q.T_world_camera, qb.T_world_camera);
  EXPECT_EQ(qb.max_visual_depth_m, q.max_visual_depth_m);

  const Submap s = randSubmap(30, 10, 3);
  const Submap sb = roundTrip<livo::submap_t>(s);
  EXPECT_EQ(sb.utime, s.utime);
  EXPECT_EQ(sb.request_id, s.request_id);
  EXPECT_EQ(sb.voxel_size_m, s.voxel_size_m);
  EXPECT_EQ(sb.next_visual_point_id, s.next_visual_point_id);
  ASSERT_EQ(sb.planes.size(), s.planes.size());
  for (std::size_t i = 0; i < s.planes.size(); ++i) expectPlaneEq(s.planes[i], sb.planes[i]);
  ASSERT_EQ(sb.visual_points.size(), s.visual_points.size());
  for (std::size_t i = 0; i < s.visual_points.size(); ++i) expectVisualPointEq(s.visual_points[i], sb.visual_points[i]);

  MapUpdate u;
  u.utime = 55;
  u.request_id = 9;
  u.T_world_imu = randPose();
  for (int i = 0; i < 200; ++i) u.points.push_back({randVec3(300), randCov<3>(0.03)});
  for (int i = 0; i < 4; ++i) u.new_visual_points.push_back(randVisualPoint(1));
  for (int i = 0; i < 6; ++i) u.observations.emplace_back(uniInt(0, 1000), randObs());
  const MapUpdate ub = roundTrip<livo::map_update_t>(u);
  EXPECT_EQ(ub.utime, u.utime);
  EXPECT_EQ(ub.request_id, u.request_id);
  expectPoseNear(u.T_world_imu, ub.T_world_imu);
  ASSERT_EQ(ub.points.size(), u.points.size());
  for (std::size_t i = 0; i < u.points.size(); ++i) {
    for (int a = 0; a < 3; ++a) EXPECT_EQ(f32(u.points[i].p_world[a]), ub.points[i].p_world[a]);  // float on the wire
    expectCov3AtFloat(u.points[i].cov_world, ub.points[i].cov_world);
  }
  ASSERT_EQ(ub.new_visual_points.size(), u.new_visual_points.size());
  for (std::size_t i = 0; i < u.new_visual_points.size(); ++i)
    expectVisualPointEq(u.new_visual_points[i], ub.new_visual_points[i]);
  ASSERT_EQ(ub.observations.size(), u.observations.size());
  for (std::size_t i = 0; i < u.observations.size(); ++i) {
    EXPECT_EQ(ub.observations[i].first, u.observations[i].first);
    expectObsEq(u.observations[i].second, ub.observations[i].second);
  }

  MapStats st;
  st.utime = 99; st.local_voxels = 1; st.local_planes = 2; st.visual_points_local = 3; st.visual_points_longterm = 4;
  st.bytes = 5ll << 32; st.bytes_cap = 6; st.evicted_visual_points = 7; st.evicted_voxels = 8; st.slides = 9;
  st.queries_answered = 10; st.last_slide_ms = 1.25f;
  const MapStats sb2 = roundTrip<livo::map_stats_t>(st);
  EXPECT_EQ(sb2.utime, 99); EXPECT_EQ(sb2.local_voxels, 1); EXPECT_EQ(sb2.local_planes, 2);
  EXPECT_EQ(sb2.visual_points_local, 3); EXPECT_EQ(sb2.visual_points_longterm, 4); EXPECT_EQ(sb2.bytes, 5ll << 32);
  EXPECT_EQ(sb2.bytes_cap, 6); EXPECT_EQ(sb2.evicted_visual_points, 7); EXPECT_EQ(sb2.evicted_voxels, 8);
  EXPECT_EQ(sb2.slides, 9); EXPECT_EQ(sb2.queries_answered, 10); EXPECT_EQ(sb2.last_slide_ms, 1.25f);
}

TEST(EstimatorMessages, RoundTripOdometryRegisteredScanStats) {
  for (int k = 0; k < 20; ++k) {
    OdometryOutput o;
    o.utime = uniInt(0, 1'800'000'000'000'000);
    o.state.utime = o.utime;
    const Pose T = randPose();
    o.state.R_world_imu = T.linear();
    o.state.p_world_imu = T.translation();
    o.state.inv_exposure = uni(0.1, 3);
    o.state.v_world = randVec3(20); o.state.bg = randVec3(0.01); o.state.ba = randVec3(0.1); o.state.g_world = randVec3(10);
    o.pose_cov = randCov<6>(0.1);
    o.status = std::int32_t(uniInt(0, odometry_status::kKnownBits));
    const OdometryOutput b = roundTrip<livo::odometry_t>(o);
    EXPECT_EQ(b.utime, o.utime);
    EXPECT_EQ(b.state.utime, o.utime);
    EXPECT_LT((b.state.R_world_imu - o.state.R_world_imu).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_TRUE(b.state.p_world_imu == o.state.p_world_imu);
    EXPECT_EQ(b.state.inv_exposure, o.state.inv_exposure);
    EXPECT_TRUE(b.state.v_world == o.state.v_world && b.state.bg == o.state.bg && b.state.ba == o.state.ba &&
                b.state.g_world == o.state.g_world);
    EXPECT_TRUE(b.pose_cov == o.pose_cov);
    EXPECT_EQ(b.status, o.status);
  }

  for (const bool colours : {false, true}) {
    RegisteredScan r;
    r.utime = 77;
    for (int i = 0; i < 500; ++i) {
      r.points.push_back(randVec3(100).cast<float>());
      r.intensity.push_back(float(uni(0, 255)));
      if (colours) r.rgb.push_back(i % 7 == 0 ? -1 : std::int32_t(uniInt(0, 0xFFFFFF)));
    }
    const RegisteredScan b = roundTrip<livo::registered_scan_t>(r);
    EXPECT_EQ(b.utime, r.utime);
    EXPECT_TRUE(b.points == r.points);
    EXPECT_EQ(b.intensity, r.intensity);
    EXPECT_EQ(b.rgb, r.rgb);
  }

  EstimatorStats s;
  s.utime = 5; s.frame_index = 6; s.lio_ms = 7.5f; s.vio_ms = 2.25f; s.map_ms = 0.5f; s.map_wait_ms = 3.25f; s.total_ms = 11.f;
  s.sigma_min = 0.125f; s.degenerate = true; s.visual_used = false; s.map_timeout = true; s.lidar_failed = true;
  s.n_points = 1000; s.n_planes_matched = 900; s.n_visual_points = 80; s.n_longterm_visual_points = 30;
  s.dropped_points = 12;
  const EstimatorStats b = roundTrip<livo::estimator_stats_t>(s);
  EXPECT_EQ(b.utime, 5); EXPECT_EQ(b.frame_index, 6); EXPECT_EQ(b.lio_ms, 7.5f); EXPECT_EQ(b.vio_ms, 2.25f);
  EXPECT_EQ(b.map_ms, 0.5f); EXPECT_EQ(b.map_wait_ms, 3.25f); EXPECT_EQ(b.total_ms, 11.f); EXPECT_EQ(b.sigma_min, 0.125f);
  EXPECT_TRUE(b.degenerate); EXPECT_FALSE(b.visual_used); EXPECT_TRUE(b.map_timeout); EXPECT_TRUE(b.lidar_failed);
  EXPECT_EQ(b.n_points, 1000); EXPECT_EQ(b.n_planes_matched, 900); EXPECT_EQ(b.n_visual_points, 80);
  EXPECT_EQ(b.n_longterm_visual_points, 30);
  EXPECT_EQ(b.dropped_points, 12);
}

TEST(MapMessages, ValidationNamesTheFieldForEveryClassOfError) {
  const livo::submap_t good = toMsg(randSubmap(4, 2, 2));
  ASSERT_TRUE(validate(good)) << validate(good).error;
  MessageLimits lim;
  livo::submap_t s = good;

  // Declared counts vs arrays, and counts vs MessageLimits.
  s.num_planes = 5;
  EXPECT_EQ(validate(s).error, "submap_t.planes: num_planes declares 5 but the array has 4 values");
  s = good; s.num_planes = -1;
  expectError(validate(s), "submap_t.num_planes", "negative count");
  s = good; lim.max_planes = 3;
  expectError(validate(s, lim), "submap_t.num_planes", "max_planes");
  lim = MessageLimits(); lim.max_patches_per_point = 1;
  expectError(validate(s, lim), "submap_t.visual_points[0].num_patches", "max_patches_per_point");
  s = good; s.visual_points[1].patches[0].values.pop_back();
  EXPECT_EQ(validate(s).error, "submap_t.visual_points[1].patches[0].values: num_values declares 432 but the array "
                               "has 431 values");

  // Finite values, unit normals, covariances.
  s = good; s.planes[1].center[2] = std::nan("");
  expectError(validate(s), "submap_t.planes[1].center[2]", "non-finite");
  s = good; for (double& n : s.planes[0].normal) n *= 1.01;
  expectError(validate(s), "submap_t.planes[0].normal", "is not 1");
  s = good; s.visual_points[0].normal[0] = INFINITY;
  expectError(validate(s), "submap_t.visual_points[0].normal[0]", "non-finite");
  s = good; s.planes[2].covariance[4][4] = -1e-3;
  expectError(validate(s), "submap_t.planes[2].covariance", "negative variance");
  s = good; s.planes[2].covariance[1][4] += 1e-3;
  expectError(validate(s), "submap_t.planes[2].covariance", "not symmetric at (1,4)");
  s = good; s.planes[2].covariance[0][5] = s.planes[2].covariance[5][0] = 10.0;
  expectError(validate(s), "submap_t.planes[2].covariance", "not positive semidefinite at (0,5)");
  s = good; s.visual_points[1].position_cov[4] = std::nanf("");
  expectError(validate(s), "submap_t.visual_points[1].position_cov", "non-finite");
  s = good; s.planes[0].radius_m = -1.f;
  expectError(validate(s), "submap_t.planes[0].radius_m");
  s = good; s.voxel_size_m = 0;
  expectError(validate(s), "submap_t.voxel_size_m");

  // Plane leaf path, reference index.
  s = good; s.planes[3].layer = 4;
  expectError(validate(s), "submap_t.planes[3].layer");
  s = good; s.planes[3].layer = 1; s.planes[3].octant[0] = 2; s.planes[3].octant[1] = 5;
  expectError(validate(s), "submap_t.planes[3].octant[1]", "unused (-1)");
  s = good; s.visual_points[0].reference = 2;
  expectError(validate(s), "submap_t.visual_points[0].reference", "outside -1..1");
  s = good; s.visual_points[0].views = s.visual_points[0].num_patches - 1;
  expectError(validate(s), "submap_t.visual_points[0].views", "fewer than num_patches");

  // Patch layout: 3 levels of 12 x 12 crops.
  livo::patch_t p = toMsg(randObs());
  ASSERT_TRUE(validate(p));
  p.levels = 2;
  expectError(validate(p), "patch_t.levels", "expected 3");
  p = toMsg(randObs()); p.size = 8;
  expectError(validate(p), "patch_t.size", "expected 12");
  p = toMsg(randObs()); p.num_values = 400; p.values.resize(400);
  EXPECT_EQ(validate(p).error, "patch_t.num_values: declares 400 but levels * size * size = 432");
  p = toMsg(randObs()); p.T_world_camera[3] = p.T_world_camera[4] = p.T_world_camera[5] = p.T_world_camera[6] = 0;
  expectError(validate(p), "patch_t.T_world_camera", "quaternion norm");
  p = toMsg(randObs()); p.inv_exposure = 0;
  expectError(validate(p), "patch_t.inv_exposure");
  p = toMsg(randObs()); p.values[100] = INFINITY;
  expectError(validate(p), "patch_t.values[100]");
  p = toMsg(randObs()); p.values[7] = 300.f;
  expectError(validate(p), "patch_t.values[7]", "gray value in [0, 255]");

  // Query and update.
  MapQuery q;
  q.keys = {{1, 2, 3}};
  livo::map_query_t qm = toMsg(q);
  ASSERT_TRUE(validate(qm));
  for (double& c : qm.orientation) c = 0;
  expectError(validate(qm), "map_query_t.orientation", "quaternion norm");
  qm = toMsg(q); qm.key_y.clear();
  EXPECT_EQ(validate(qm).error, "map_query_t.key_y: num_keys declares 1 but the array has 0 values");
  qm = toMsg(q); qm.radius_m = std::nan("");
  expectError(validate(qm), "map_query_t.radius_m");

  MapUpdate u;
  for (int i = 0; i < 5; ++i) u.points.push_back({randVec3(10), randCov<3>(0.1)});
  u.observations.emplace_back(3, randObs());
  const livo::map_update_t ug = toMsg(u);
  ASSERT_TRUE(validate(ug));
  livo::map_update_t um = ug;
  um.y[3] = std::nanf("");
  expectError(validate(um), "map_update_t.y[3]", "non-finite");
  um = ug; um.cov_xy[2] = 1e3f;
  expectError(validate(um), "map_update_t.cov_xx..cov_zz[2]", "not positive semidefinite");
  um = ug; um.cov_zz[4] = -1.f;
  expectError(validate(um), "map_update_t.cov_xx..cov_zz[4]", "negative variance");
  um = ug; um.observation_point_ids.push_back(4);
  EXPECT_EQ(validate(um).error, "map_update_t.observation_point_ids: num_observations declares 1 but the array has 2 "
                                "values");
  um = ug; um.observations[0].levels = 1;
  expectError(validate(um), "map_update_t.observations[0].levels");

  livo::map_stats_t ms = toMsg(MapStats());
  ms.evicted_voxels = -1;
  expectError(validate(ms), "map_stats_t.evicted_voxels", "negative");
}

TEST(EstimatorMessages, ValidationNamesTheField) {
  OdometryOutput o;
  o.pose_cov = randCov<6>(0.1);
  const livo::odometry_t og = toMsg(o);
  ASSERT_TRUE(validate(og));
  livo::odometry_t om = og;
  om.status = 256;
  expectError(validate(om), "odometry_t.status", "unknown bits");
  om = og; om.velocity[1] = std::nan("");
  expectError(validate(om), "odometry_t.velocity[1]");
  om = og; om.inv_exposure = -1;
  expectError(validate(om), "odometry_t.inv_exposure");
  om = og; om.covariance[3][3] = -0.1;
  EXPECT_EQ(validate(om).error, "odometry_t.covariance: negative variance -0.1 at (3,3)");
  om = og; for (double& c : om.orientation) c = 0;
  expectError(validate(om), "odometry_t.orientation");

  RegisteredScan r;
  r.points = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(4, 5, 6)};
  r.intensity = {1, 2};
  r.rgb = {0x112233, -1};
  const livo::registered_scan_t rg = toMsg(r);
  ASSERT_TRUE(validate(rg));
  livo::registered_scan_t rm = rg;
  rm.num_colors = 1; rm.rgb.resize(1);
  expectError(validate(rm), "registered_scan_t.num_colors", "0 or num_points");
  rm = rg; rm.rgb[1] = 0x1000000;
  expectError(validate(rm), "registered_scan_t.rgb[1]");
  rm = rg; rm.z[0] = INFINITY;
  expectError(validate(rm), "registered_scan_t.z[0]");
  rm = rg; rm.intensity.push_back(1);
  EXPECT_EQ(validate(rm).error, "registered_scan_t.intensity: num_points declares 2 but the array has 3 values");
  MessageLimits lim;
  lim.max_points = 1;
  expectError(validate(rg, lim), "registered_scan_t.num_points", "max_points");

  livo::estimator_stats_t es = toMsg(EstimatorStats());
  es.lio_ms = -1.f;
  expectError(validate(es), "estimator_stats_t.lio_ms");
  es = toMsg(EstimatorStats()); es.map_wait_ms = -0.5f;
  expectError(validate(es), "estimator_stats_t.map_wait_ms");
  es = toMsg(EstimatorStats()); es.n_planes_matched = -3;
  expectError(validate(es), "estimator_stats_t.n_planes_matched");
  es = toMsg(EstimatorStats()); es.n_visual_points = 4; es.n_longterm_visual_points = 5;
  expectError(validate(es), "estimator_stats_t.n_longterm_visual_points", "more than n_visual_points");
  es = toMsg(EstimatorStats()); es.health = 4;
  expectError(validate(es), "estimator_stats_t.health", "not 0..3");
  es = toMsg(EstimatorStats()); es.health_reason.assign(513, 'x');
  expectError(validate(es), "estimator_stats_t.health_reason", "above 512");
  EstimatorStats lost;
  lost.health = 3;
  lost.health_reason = "matched 3 of 900 covered points";
  EstimatorStats back;
  ASSERT_TRUE(fromMsg(toMsg(lost), back));
  EXPECT_EQ(back.health, 3);
  EXPECT_EQ(back.health_reason, lost.health_reason);

  // A NUL inside a string decodes, but LCM's C++ encoder stops at it while sizing the message by the
  // string's length: decode rejects it (the fuzz test found one on arm64), and a string without its NUL.
  livo::estimator_stats_t named = toMsg(EstimatorStats());
  named.health_reason = "abcdef";
  std::vector<std::uint8_t> bytes = encode(named);  // the string's 6 bytes and its NUL come last
  livo::estimator_stats_t decoded;
  ASSERT_TRUE(decode(bytes.data(), bytes.size(), decoded));
  bytes[bytes.size() - 4] = 0;  // 'd'
  expectError(decode(bytes.data(), bytes.size(), decoded), "estimator_stats_t.health_reason", "NUL byte at 3 of 6");
  bytes[bytes.size() - 4] = 'd';
  bytes.back() = 'x';
  expectError(decode(bytes.data(), bytes.size(), decoded), "estimator_stats_t.health_reason", "without its terminating NUL");
}

TEST(MessageConversions, FromMsgLeavesOutputUntouchedAndDecodePathReportsField) {
  livo::submap_t bad = toMsg(randSubmap(2, 1, 1));
  bad.planes[1].normal[0] = 5;
  Submap out;
  out.request_id = 1234;
  EXPECT_FALSE(fromMsg(bad, out));
  EXPECT_EQ(out.request_id, 1234);
  EXPECT_TRUE(out.planes.empty());

  // A message that passes the byte-level precheck but not validation.
  const auto buf = encode(bad);
  livo::submap_t dec{};
  ASSERT_TRUE(decode(buf.data(), buf.size(), dec));
  expectError(fromMsg(dec, out), "submap_t.planes[1].normal", "is not 1");
}

TEST(MessageConversions, ToMsgRejectsWhatTheMessageCannotCarry) {
  MapQuery q;
  q.keys = {{0, 0, 0}, {1, std::int64_t(INT32_MAX) + 1, 0}};
  try {
    toMsg(q);
    ADD_FAILURE() << "expected std::out_of_range";
  } catch (const std::out_of_range& e) {
    EXPECT_EQ(std::string(e.what()).rfind("map_query_t.keys[1]: voxel key (1, 2147483648, 0)", 0), 0u) << e.what();
  }
  Submap s = randSubmap(3, 0, 0);
  s.planes[2].key.z = std::int64_t(INT32_MIN) - 1;
  try {
    toMsg(s);
    ADD_FAILURE() << "expected std::out_of_range";
  } catch (const std::out_of_range& e) {
    EXPECT_EQ(std::string(e.what()).rfind("submap_t.planes[2]", 0), 0u) << e.what();
  }
  RegisteredScan r;
  r.points.resize(3);
  r.intensity.resize(2);
  EXPECT_THROW(toMsg(r), std::invalid_argument);
  r.intensity.resize(3);
  r.rgb.resize(1);
  EXPECT_THROW(toMsg(r), std::invalid_argument);
}

// Encoded sizes for a large submap (oracle: the field sizes of lcmtypes/*.lcm; LCM adds no padding).
TEST(MapMessages, LargeSubmapEncodesAndDecodes) {
  constexpr std::size_t kPlaneBytes = 3 * 4 + 1 + 3 + 3 * 8 + 3 * 8 + 36 * 8 + 4 + 4 + 4 + 1;       // 365
  constexpr std::size_t kPatchBytes = 8 + 1 + 1 + 4 + 432 * 4 + 7 * 8 + 2 * 4 + 4 + 4;             // 1814
  constexpr std::size_t kPointBytes = 8 + 3 * 8 + 3 * 8 + 6 * 4 + 1 + 4 + 4 + 4 + 1 + 4;            // 98 + patches
  std::size_t empty = 0;
  roundTrip<livo::submap_t>(Submap(), &empty);
  for (const int n_obs : {1, 8}) {
    const Submap s = randSubmap(10000, 1000, n_obs);
    std::size_t bytes = 0;
    const Submap b = roundTrip<livo::submap_t>(s, &bytes);
    ASSERT_EQ(b.planes.size(), 10000u);
    ASSERT_EQ(b.visual_points.size(), 1000u);
    expectPlaneEq(s.planes[9999], b.planes[9999]);
    expectVisualPointEq(s.visual_points[999], b.visual_points[999]);
    const std::size_t per_point = kPointBytes + std::size_t(n_obs) * kPatchBytes;
    EXPECT_EQ(bytes, empty + 10000 * kPlaneBytes + 1000 * per_point);
    std::printf("[ sizes    ] submap of 10000 planes + 1000 visual points with %d observation(s): %zu bytes "
                "(%zu per plane, %zu per visual point, %zu per patch, %zu header)\n",
                n_obs, bytes, kPlaneBytes, per_point, kPatchBytes, empty);
  }
}

// The covariance checks must accept what the real producers emit: planes from libs/map's fitPlane
// (rank-deficient normal block, axis-aligned and noise-free planes included) and the filter's
// initial covariance.
TEST(MessageConversions, RealProducersPassValidation) {
  const Vec3 normals[] = {Vec3::UnitZ(), Vec3::UnitX(), Vec3(1, 1, 0).normalized(), randUnit(), randUnit()};
  for (const Vec3& n : normals)
    for (const double noise : {0.0, 0.01}) {
      const Vec3 u = n.unitOrthogonal(), v = n.cross(u), q0 = randVec3(50);
      std::vector<PointWithCov> pts;
      for (int i = 0; i < 40; ++i) {
        PointWithCov p;
        p.p_world = q0 + uni(-0.2, 0.2) * u + uni(-0.2, 0.2) * v + noise * uni(-1, 1) * n;
        p.cov_world = pointCovarianceBody(p.p_world - q0 + Vec3(0, 0, 5), 0.02, 0.1);
        pts.push_back(p);
      }
      SubmapPlane s;
      ASSERT_TRUE(fitPlane(pts, 0.01, s.plane));
      const Validation v1 = validate(toMsg(s));
      EXPECT_TRUE(v1) << v1.error << " (noise " << noise << ")";
    }
  OdometryOutput o;
  o.pose_cov = initialCovariance().topLeftCorner<6, 6>();
  EXPECT_TRUE(validate(toMsg(o)));
}
