// libs/map visual map, part 2: observation-add rules (against the newest observation), the
// max-observation policy, reference selection against a brute-force score, normal refinement and
// convergence with a LiDAR plane map, outlier removal, memory accounting, extract/insert, config.
#include "livo/common/config.hpp"
#include "livo/map/visual_map.hpp"
#include "livo/map/visual_map_scores.hpp"
#include "livo/map/voxel_map.hpp"
#include "livo/sensors/camera_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

using namespace livo;

namespace {

constexpr int kW = 640, kH = 480;

// Random texture T(x - ox, y - oy) (values 20..235): the patch at (ox, oy) + d is the same for every
// offset, so observations at different pixels can carry the same patch.
Image textureAt(double ox, double oy, unsigned seed, double noise_sigma = 0.0, unsigned noise_seed = 0) {
  Image im;
  im.width = kW;
  im.height = kH;
  im.row_stride = kW;
  im.format = PixelFormat::Gray8;
  im.data.resize(std::size_t(kW) * kH);
  std::mt19937 noise_rng(noise_seed);
  std::normal_distribution<double> noise(0.0, noise_sigma > 0.0 ? noise_sigma : 1.0);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      // Hash of the texture coordinates: a fixed pseudo-random field.
      std::uint32_t h = std::uint32_t(int(x - ox) + 4096) * 73856093u ^ std::uint32_t(int(y - oy) + 4096) * 19349663u ^ seed;
      h ^= h >> 13;
      h *= 0x5bd1e995u;
      h ^= h >> 15;
      double v = 20.0 + double(h % 216u);
      if (noise_sigma > 0.0) v += noise(noise_rng);
      im.data[std::size_t(y) * kW + std::size_t(x)] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
  return im;
}

Pose cameraAt(const Vec3& t) { return Pose(Eigen::Translation3d(t)); }

// A point at (0, 0, 5) facing a camera at the origin, with one observation of `im` at `px`.
VisualPoint pointWithObservation(const Image& im, const Vec2& px) {
  VisualPoint p;
  p.id = 1;
  p.p_world = Vec3(0, 0, 5);
  p.normal = Vec3(0, 0, -1);
  p.obs.emplace_back();
  EXPECT_TRUE(extractPatchPyramid(im, px, p.obs[0].patch));
  p.obs[0].px = px;
  p.reference = 0;
  return p;
}

double bruteNcc(const PatchPyramid& a, const PatchPyramid& b) {
  double ma = 0, mb = 0;
  const int m = PatchPyramid::kMargin, s = PatchPyramid::kSize;
  for (int r = m; r < m + s; ++r)
    for (int c = m; c < m + s; ++c) {
      ma += a.at(0, r, c) / 64.0;
      mb += b.at(0, r, c) / 64.0;
    }
  double ab = 0, aa = 0, bb = 0;
  for (int r = m; r < m + s; ++r)
    for (int c = m; c < m + s; ++c) {
      ab += (a.at(0, r, c) - ma) * (b.at(0, r, c) - mb);
      aa += (a.at(0, r, c) - ma) * (a.at(0, r, c) - ma);
      bb += (b.at(0, r, c) - mb) * (b.at(0, r, c) - mb);
    }
  return ab / std::sqrt(aa * bb);
}

}  // namespace

TEST(VisualObservations, AddRulesCompareWithNewestObservation) {
  VisualMap map;
  const Image im = textureAt(0, 0, 1);
  const Vec2 px(320, 240);
  VisualPoint p = pointWithObservation(im, px);
  p.obs[0].T_world_camera = cameraAt(Vec3::Zero());
  // Small motion: 0.1 m sideways (ray turn 0.02 rad), same pixel: no.
  EXPECT_FALSE(map.addObservation(p, im, cameraAt(Vec3(0.1, 0, 0)), px, 1.f, 10));
  EXPECT_EQ(p.last_seen, 10);
  // 0.6 m forward along the ray (no turn, no shift): yes.
  EXPECT_TRUE(map.addObservation(p, im, cameraAt(Vec3(0, 0, 0.6)), px, 1.f, 20));
  ASSERT_EQ(p.obs.size(), 2u);
  EXPECT_EQ(p.obs.back().utime, 20);
  // 0.65 m from the oldest but 0.05 m from the newest: no (the reference code compared with the oldest).
  EXPECT_FALSE(map.addObservation(p, im, cameraAt(Vec3(0, 0, 0.65)), px, 1.f, 30));
  // Turn of the view ray above 0.3 rad with a 0.45 m move: the point is 1 m in front of that camera.
  VisualPoint q = pointWithObservation(im, px);
  q.p_world = Vec3(0, 0, 1);
  q.obs[0].T_world_camera = cameraAt(Vec3::Zero());
  EXPECT_FALSE(map.addObservation(q, im, cameraAt(Vec3(0.28, 0, 0)), px, 1.f, 1));  // atan(0.28) = 0.27 rad
  EXPECT_TRUE(map.addObservation(q, im, cameraAt(Vec3(0.45, 0, 0)), px, 1.f, 2));   // atan(0.45) = 0.42 rad
  // Pixel shift: 39 px no, 41 px yes (same pose).
  VisualPoint r = pointWithObservation(im, px);
  EXPECT_FALSE(map.addObservation(r, im, Pose::Identity(), px + Vec2(39, 0), 1.f, 1));
  EXPECT_TRUE(map.addObservation(r, im, Pose::Identity(), px + Vec2(0, 41), 1.f, 2));
  EXPECT_LT((r.obs.back().px - (px + Vec2(0, 41))).norm(), 1e-12);
  // A pixel whose crops leave the image: not added.
  EXPECT_FALSE(map.addObservation(r, im, Pose::Identity(), Vec2(5, 5), 1.f, 3));
  // Converged points are frozen.
  r.converged = true;
  EXPECT_FALSE(map.addObservation(r, im, cameraAt(Vec3(5, 0, 0)), px, 1.f, 4));
}

TEST(VisualObservations, MaxObservationsDropsLowestScoreNeverReference) {
  VisualMapConfig cfg;
  cfg.max_observations = 3;
  VisualMap map(cfg);
  // obs 0: unrelated texture; obs 1, 2: texture 5 (obs 1 is the reference); new obs 3: texture 5.
  VisualPoint p = pointWithObservation(textureAt(100, 100, 99), Vec2(100, 100));
  ASSERT_TRUE(map.addObservation(p, textureAt(150, 100, 5), Pose::Identity(), Vec2(150, 100), 1.f, 1));
  ASSERT_TRUE(map.addObservation(p, textureAt(200, 100, 5, 4.0, 1), Pose::Identity(), Vec2(200, 100), 1.f, 2));
  p.reference = 1;
  ASSERT_TRUE(map.addObservation(p, textureAt(250, 100, 5, 4.0, 2), Pose::Identity(), Vec2(250, 100), 1.f, 3));
  ASSERT_EQ(p.obs.size(), 3u);
  EXPECT_EQ(p.obs[0].px.x(), 150.0);  // the unrelated one went; the reference index followed
  EXPECT_EQ(p.reference, 0);
  EXPECT_EQ(p.obs[2].px.x(), 250.0);  // the new one stays

  // Unrelated reference: it survives, the weaker of the other old ones goes.
  VisualPoint q = pointWithObservation(textureAt(100, 100, 99), Vec2(100, 100));  // reference 0
  ASSERT_TRUE(map.addObservation(q, textureAt(150, 100, 5, 80.0, 3), Pose::Identity(), Vec2(150, 100), 1.f, 1));
  ASSERT_TRUE(map.addObservation(q, textureAt(200, 100, 5, 2.0, 4), Pose::Identity(), Vec2(200, 100), 1.f, 2));
  ASSERT_TRUE(map.addObservation(q, textureAt(250, 100, 5, 2.0, 5), Pose::Identity(), Vec2(250, 100), 1.f, 3));
  ASSERT_EQ(q.obs.size(), 3u);
  EXPECT_EQ(q.reference, 0);
  EXPECT_EQ(q.obs[0].px.x(), 100.0);
  EXPECT_EQ(q.obs[1].px.x(), 200.0);  // the noisy copy (sigma 80) scored lowest
  EXPECT_EQ(q.obs[2].px.x(), 250.0);

  // Many additions with the default limit: the vector never holds more than max_observations + 1.
  VisualMap defaults;
  VisualPoint r = pointWithObservation(textureAt(100, 100, 5), Vec2(100, 100));
  for (int i = 1; i < 40; ++i) {
    const Vec2 px(100.0 + 50.0 * (i % 9), 100.0 + 50.0 * (i / 9));
    ASSERT_TRUE(defaults.addObservation(r, textureAt(px.x(), px.y(), 5, 3.0, unsigned(i)), Pose::Identity(), px, 1.f, i));
    EXPECT_LE(r.obs.size(), std::size_t(defaults.config().max_observations));
    EXPECT_LE(r.obs.capacity(), std::size_t(defaults.config().max_observations) + 1);
  }
}

TEST(VisualReference, PicksObservationAgreeingBestWithOthers) {
  VisualMap map;
  // Five observations of the same texture with different noise, one unrelated; all from cameras on
  // a ring 5 m in front of the point at different angles to the normal.
  VisualPoint p;
  p.id = 3;
  p.p_world = Vec3(0, 0, 5);
  p.normal = Vec3(0, 0, -1);
  const double sigmas[] = {25.0, 3.0, 10.0, 0.0, 18.0, 0.0};
  for (int i = 0; i < 6; ++i) {
    const Vec2 px(100.0 + 60.0 * i, 200.0);
    const Image im = textureAt(px.x(), px.y(), i == 5 ? 77u : 5u, sigmas[i], unsigned(10 + i));
    VisualObservation o;
    ASSERT_TRUE(extractPatchPyramid(im, px, o.patch));
    o.px = px;
    const double a = 0.05 * i;
    o.T_world_camera = cameraAt(Vec3(0, 0, 5) + 5.0 * Vec3(std::sin(a), 0, -std::cos(a)));
    p.obs.push_back(o);
  }
  p.reference = 5;
  // Oracle: mean |NCC| to the others + cos(ray to the camera, normal), by brute force.
  int expected = -1;
  double best = -1e9;
  for (int i = 0; i < 6; ++i) {
    double s = 0;
    for (int j = 0; j < 6; ++j)
      if (j != i) s += std::abs(bruteNcc(p.obs[std::size_t(i)].patch, p.obs[std::size_t(j)].patch)) / 5.0;
    s += (p.obs[std::size_t(i)].T_world_camera.translation() - p.p_world).normalized().dot(p.normal);
    if (s > best) {
      best = s;
      expected = i;
    }
  }
  map.refine(p, nullptr);
  EXPECT_EQ(p.reference, expected);
  EXPECT_NE(p.reference, 5);
  EXPECT_NEAR(p.obs[std::size_t(expected)].score, best, 1e-5);
  EXPECT_FALSE(p.converged);  // no LiDAR map: no normal refinement, no convergence
  EXPECT_EQ(p.obs.size(), 6u);
}

TEST(VisualReference, NormalFromLidarPlaneThenConverges) {
  // A LiDAR plane z = 5.1 (normal +-z) around the point.
  VoxelMap lidar;
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(0.02, 0.48);
  std::normal_distribution<double> n(0.0, 0.002);
  std::vector<PointWithCov> pts;
  for (int i = 0; i < 40; ++i) {
    PointWithCov pw;
    pw.p_world = Vec3(u(rng), u(rng), 5.1 + n(rng));
    pw.cov_world = 4e-6 * Mat3::Identity();
    pts.push_back(pw);
  }
  lidar.insert(pts);
  ASSERT_GT(lidar.numPlanes(), 0u);

  VisualMapConfig cfg;
  cfg.refine_min_observations = 3;
  cfg.converge_min_observations = 4;
  VisualMap map(cfg);
  auto p = std::make_unique<VisualPoint>();
  p->id = 9;
  p->p_world = Vec3(0.25, 0.25, 5.1);
  p->cov = 1e-4 * Mat3::Identity();
  p->normal = Vec3(0.2, 0.0, -1.0).normalized();  // facing the cameras below the plane
  for (int i = 0; i < 4; ++i) {
    const Vec2 px(100.0 + 60.0 * i, 200.0);
    VisualObservation o;
    ASSERT_TRUE(extractPatchPyramid(textureAt(px.x(), px.y(), 5, 2.0, unsigned(i)), px, o.patch));
    o.px = px;
    o.T_world_camera = cameraAt(Vec3(0.1 * i, 0, 0));
    p->obs.push_back(o);
  }
  p->reference = 0;
  VisualPoint* raw = p.get();
  ASSERT_TRUE(map.insert(std::move(p)));
  const std::size_t bytes_before = map.bytes();

  // Two observations only: below refine_min_observations, the normal is kept.
  VisualPoint two = *raw;
  two.obs.resize(2);
  map.refine(two, &lidar);
  EXPECT_LT((two.normal - Vec3(0.2, 0.0, -1.0).normalized()).norm(), 1e-12);

  map.refine(*raw, &lidar);  // normal := plane normal with the previous sign
  EXPECT_LT((raw->normal - Vec3(0, 0, -1)).norm(), 0.02);
  EXPECT_FALSE(raw->converged);
  const int ref = raw->reference;
  const Vec2 ref_px = raw->obs[std::size_t(ref)].px;
  map.refine(*raw, &lidar);  // unchanged plane: converged, only the reference kept
  EXPECT_TRUE(raw->converged);
  ASSERT_EQ(raw->obs.size(), 1u);
  EXPECT_EQ(raw->reference, 0);
  EXPECT_EQ(raw->obs[0].px, ref_px);
  EXPECT_LT(map.bytes() + 3 * sizeof(VisualObservation), bytes_before + 1);
}

TEST(VisualOutliers, ConsecutiveBadUpdatesRemovePoint) {
  VisualMapConfig cfg;
  cfg.max_bad_updates = 2;
  VisualMap map(cfg);
  for (int i = 1; i <= 3; ++i) {
    auto p = std::make_unique<VisualPoint>();
    p->id = i;
    p->p_world = Vec3(i, 0, 0);
    map.insert(std::move(p));
  }
  VisualPoint* a = map.find(1);
  VisualPoint* b = map.find(2);
  for (int k = 0; k < 2; ++k) map.reportPhotometricError(*a, 500.0, 100.0);
  map.reportPhotometricError(*a, 50.0, 100.0);  // a good update resets the count
  EXPECT_EQ(a->bad_updates, 0);
  for (int k = 0; k < 2; ++k) map.reportPhotometricError(*a, 500.0, 100.0);
  map.reportPhotometricError(*b, std::nan(""), 100.0);  // NaN counts as bad
  for (int k = 0; k < 2; ++k) map.reportPhotometricError(*b, 500.0, 100.0);
  EXPECT_EQ(b->bad_updates, 3);
  EXPECT_EQ(map.removeBadPoints(), 1u);  // b is over 2; a is at 2
  EXPECT_EQ(map.find(2), nullptr);
  EXPECT_EQ(map.find(1), a);  // other points' pointers stay valid
  EXPECT_EQ(map.size(), 2u);
  EXPECT_EQ(map.removeBadPoints(), 0u);
}

TEST(VisualHousekeeping, BytesExtractInsertAndBox) {
  const auto cam = CameraModel::create([] {
    CameraConfig c;
    c.enabled = true;
    c.width = kW;
    c.height = kH;
    c.fx = c.fy = 400;
    c.cx = 319.5;
    c.cy = 239.5;
    return c;
  }());
  VisualMap map;
  const std::size_t empty = map.bytes();
  const Image im = textureAt(0, 0, 3);
  std::vector<NewPointCandidate> cands;
  for (int r = 0; r < 12; ++r)
    for (int c = 0; c < 18; ++c) {
      NewPointCandidate nc;
      const double z = 3.0 + 0.1 * c;
      nc.p_world = Vec3((45.0 + 30.0 * c - 319.5) / 400.0 * z, (45.0 + 30.0 * r - 239.5) / 400.0 * z, z);
      nc.normal_world = Vec3(0, 0, -1);
      cands.push_back(nc);
    }
  const int created = map.addPoints(im, *cam, Pose::Identity(), 1.f, 5, cands, {});
  ASSERT_GT(created, 150);
  const std::size_t full = map.bytes();
  const double per_point = double(full - empty) / created;
  std::cout << "[figure] VisualMap: " << created << " points with 1 observation: " << full - empty << " bytes, "
            << per_point << " bytes/point; sizeof(VisualPoint) " << sizeof(VisualPoint) << ", sizeof(VisualObservation) "
            << sizeof(VisualObservation) << "\n";
  EXPECT_GT(per_point, double(sizeof(VisualPoint) + sizeof(VisualObservation)));
  EXPECT_LT(per_point, double(sizeof(VisualPoint) + sizeof(VisualObservation)) + 200.0);

  // Extract / insert round trip: same point, same id, found again by retrieval.
  std::vector<Vec3> scan;
  map.forEach([&](const VisualPoint& p) { scan.push_back(p.p_world); });
  const std::size_t in_view = map.retrieve(*cam, Pose::Identity(), scan).points.size();
  const std::int64_t id = map.retrieve(*cam, Pose::Identity(), scan).points.front()->id;
  std::unique_ptr<VisualPoint> out = map.extract(id);
  ASSERT_NE(out, nullptr);
  EXPECT_EQ(map.find(id), nullptr);
  EXPECT_EQ(map.size(), std::size_t(created) - 1);
  EXPECT_LT(map.bytes(), full);
  EXPECT_EQ(map.retrieve(*cam, Pose::Identity(), scan).points.size(), in_view - 1);
  const VisualPoint* raw = out.get();
  const Vec3 pos = out->p_world;
  EXPECT_TRUE(map.insert(std::move(out)));
  EXPECT_EQ(map.find(id), raw);
  EXPECT_EQ(map.find(id)->p_world, pos);
  EXPECT_EQ(map.retrieve(*cam, Pose::Identity(), scan).points.size(), in_view);
  EXPECT_FALSE(map.insert(std::make_unique<VisualPoint>(*raw)));  // id taken
  EXPECT_FALSE(map.insert(nullptr));
  auto far = std::make_unique<VisualPoint>();
  far->id = 100000;
  far->p_world = Vec3(50, 0, 0);
  EXPECT_TRUE(map.insert(std::move(far)));
  EXPECT_EQ(map.addPoints(im, *cam, Pose::Identity(), 1.f, 6, {cands[0]}, {}), 1);
  EXPECT_NE(map.find(100001), nullptr);  // new ids stay above inserted ones

  // idsOutsideBox: brute force by voxel centre.
  const Vec3 center(0.3, -0.2, 3.4);
  const double half = 1.1;
  std::vector<std::int64_t> expected;
  map.forEach([&](const VisualPoint& p) {
    const Vec3 c = map.keyOf(p.p_world).center(map.config().voxel_size_m);
    if (((c - center).cwiseAbs().array() > half).any()) expected.push_back(p.id);
  });
  std::sort(expected.begin(), expected.end());
  const std::vector<std::int64_t> got = map.idsOutsideBox(center, half);
  EXPECT_EQ(got, expected);
  EXPECT_GT(got.size(), 10u);
  EXPECT_LT(got.size(), map.size());
  for (std::int64_t i : got) map.extract(i);
  EXPECT_TRUE(map.idsOutsideBox(center, half).empty());
  map.clear();
  EXPECT_EQ(map.size(), 0u);
  EXPECT_EQ(map.numVoxels(), 0u);
}

TEST(VisualMapConfig, LoadsVioSectionAndNamesBadKeys) {
  auto f = ConfigFile::parse(
      "vio:\n  voxel_size_m: 0.4\n  grid_cell_px: 32\n  max_observations: 10\n  new_obs_min_angle_deg: 20\n"
      "  occlusion_depth_m: 0.3\n  max_bad_updates: 5\n",
      "rig.yaml");
  VisualMapConfig c;
  c.load(f.root().section("vio"));
  EXPECT_EQ(c.voxel_size_m, 0.4);
  EXPECT_EQ(c.grid_cell_px, 32);
  EXPECT_EQ(c.max_observations, 10);
  EXPECT_EQ(c.new_obs_min_angle_deg, 20.0);
  EXPECT_EQ(c.occlusion_depth_m, 0.3);
  EXPECT_EQ(c.max_bad_updates, 5);
  EXPECT_EQ(c.border_px, VisualMapConfig::kMinBorderPx);
  EXPECT_NO_THROW(f.checkAllKeysUsed());
  auto bad = ConfigFile::parse("vio:\n  border_px: 10\n", "rig.yaml");
  try {
    VisualMapConfig b;
    b.load(bad.root().section("vio"));
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("vio.border_px"), std::string::npos) << e.what();
  }
  VisualMapConfig wrong;
  wrong.max_observations = 1;
  EXPECT_THROW(VisualMap{wrong}, std::invalid_argument);
}
