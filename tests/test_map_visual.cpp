// libs/map visual map, part 1: patch pyramids against direct bilinear reads (and the border rule at
// every image edge), Shi-Tomasi and NCC against brute force, creation (Shi-Tomasi choice per cell,
// points behind the camera), retrieval against a brute-force projection of every point (voxel
// membership, per-cell choice, occlusion), the occlusion rule on a synthetic depth setup, and the
// retrieval time. Part 2 (test_map_visual_rules.cpp): observations, reference, outliers, housekeeping.
#include "livo/common/timing.hpp"
#include "livo/map/visual_map.hpp"
#include "livo/map/visual_map_scores.hpp"
#include "livo/sensors/camera_model.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <set>

using namespace livo;

namespace {

constexpr int kW = 640, kH = 480;

CameraConfig pinholeConfig() {
  CameraConfig c;
  c.enabled = true;
  c.model = CameraKind::Pinhole;
  c.width = kW;
  c.height = kH;
  c.fx = c.fy = 400.0;
  c.cx = 319.5;
  c.cy = 239.5;
  return c;
}

std::unique_ptr<CameraModel> pinhole() { return CameraModel::create(pinholeConfig()); }

Image makeImage(int w, int h, const std::function<double(double, double)>& f) {
  Image im;
  im.width = w;
  im.height = h;
  im.row_stride = w;
  im.format = PixelFormat::Gray8;
  im.data.resize(std::size_t(w) * std::size_t(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      im.data[std::size_t(y) * std::size_t(w) + std::size_t(x)] =
          static_cast<std::uint8_t>(std::clamp(std::lround(f(x, y)), 0L, 255L));
  return im;
}

// Random texture (values 20..235, fixed seed).
Image noiseImage(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> u(20, 235);
  Image im = makeImage(w, h, [](double, double) { return 0.0; });
  for (auto& v : im.data) v = static_cast<std::uint8_t>(u(rng));
  return im;
}

double pixelAt(const Image& im, int x, int y) { return im.data[std::size_t(y) * std::size_t(im.row_stride) + std::size_t(x)]; }

// World point seen at pixel `px` at depth z by a camera at T_world_camera (pinhole of pinholeConfig).
Vec3 pointAtPixel(const Pose& T_world_camera, const Vec2& px, double z) {
  const CameraConfig c = pinholeConfig();
  return T_world_camera * Vec3((px.x() - c.cx) / c.fx * z, (px.y() - c.cy) / c.fy * z, z);
}

std::unique_ptr<VisualPoint> simplePoint(std::int64_t id, const Vec3& p, bool with_reference = true) {
  auto vp = std::make_unique<VisualPoint>();
  vp->id = id;
  vp->p_world = p;
  if (with_reference) {
    vp->obs.emplace_back();
    vp->reference = 0;
  }
  return vp;
}

}  // namespace

TEST(VisualPatch, PyramidMatchesDirectBilinearReads) {
  const Image im = makeImage(kW, kH, [](double x, double y) {
    return 128.0 + 60.0 * std::sin(0.13 * x + 0.05 * y) + 50.0 * std::cos(0.07 * y - 0.11 * x);
  });
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(60.0, kW - 61.0), uy(60.0, kH - 61.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec2 px(ux(rng), uy(rng));
    PatchPyramid pyr;
    ASSERT_TRUE(extractPatchPyramid(im, px, pyr));
    for (int l = 0; l < PatchPyramid::kLevels; ++l) {
      const double stride = double(1 << l);
      for (int r = 0; r < PatchPyramid::kCrop; ++r) {
        for (int c = 0; c < PatchPyramid::kCrop; ++c) {
          // Direct bilinear read of the image at the sample position (oracle written out here).
          const double x = px.x() + (c - 0.5 * (PatchPyramid::kCrop - 1)) * stride;
          const double y = px.y() + (r - 0.5 * (PatchPyramid::kCrop - 1)) * stride;
          const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
          const double ax = x - x0, ay = y - y0;
          const double v = (1 - ay) * ((1 - ax) * pixelAt(im, x0, y0) + ax * pixelAt(im, x0 + 1, y0)) +
                           ay * ((1 - ax) * pixelAt(im, x0, y0 + 1) + ax * pixelAt(im, x0 + 1, y0 + 1));
          // Stored as whole gray levels: the read rounded to the nearest.
          ASSERT_NEAR(pyr.at(l, r, c), v, 0.5 + 1e-4) << "level " << l << " r " << r << " c " << c;
          ASSERT_EQ(pyr.at(l, r, c), std::floor(pyr.at(l, r, c)));
        }
      }
      // The patch proper is the crop without its margin, on the offsets patchOffset(i).
      const PatchValues patch = patchOfLevel(pyr, l);
      float direct = 0.f;
      ASSERT_TRUE(sampleBilinear(im, px.x() + patchOffset(3) * stride, px.y() + patchOffset(5) * stride, direct));
      EXPECT_NEAR(patch[5 * PatchPyramid::kSize + 3], direct, 0.5 + 1e-4);
    }
  }
}

// Patches are stored as whole gray levels (PyramidMatchesDirectBilinearReads: within half a level of
// the bilinear read); the rounding rule at the ends and for values that are not gray levels.
TEST(VisualPatch, SamplesRoundToTheNearestGrayLevel) {
  EXPECT_EQ(PatchPyramid::quantize(-3.f), 0);
  EXPECT_EQ(PatchPyramid::quantize(std::numeric_limits<float>::quiet_NaN()), 0);
  EXPECT_EQ(PatchPyramid::quantize(0.49f), 0);
  EXPECT_EQ(PatchPyramid::quantize(0.5f), 1);
  EXPECT_EQ(PatchPyramid::quantize(254.49f), 254);
  EXPECT_EQ(PatchPyramid::quantize(254.5f), 255);
  EXPECT_EQ(PatchPyramid::quantize(1e9f), 255);
  EXPECT_EQ(sizeof(PatchPyramid), std::size_t(PatchPyramid::kValues));
}

TEST(VisualPatch, BorderKeepsEverySampleInside) {
  // Any pixel the map accepts (inside border_px) must give a full pyramid and a Shi-Tomasi box; a
  // point just beyond the smallest border at the coarsest level would not.
  const auto cam = pinhole();
  const Image im = noiseImage(kW, kH, 3);
  const double b = VisualMapConfig{}.border_px;
  EXPECT_GE(b, VisualMapConfig::kMinBorderPx);
  EXPECT_GE(VisualMapConfig::kMinBorderPx, 0.5 * (PatchPyramid::kCrop - 1) * (1 << (PatchPyramid::kLevels - 1)) + 1);
  const double xs[] = {b, 0.5 * kW, kW - 1 - b}, ys[] = {b, 0.5 * kH, kH - 1 - b};
  for (double x : xs) {
    for (double y : ys) {
      const Vec2 px(x, y);
      ASSERT_TRUE(cam->inImage(px, b));
      PatchPyramid pyr;
      EXPECT_TRUE(extractPatchPyramid(im, px, pyr)) << px.transpose();
      EXPECT_GE(shiTomasiScore(im, px), 0.0) << px.transpose();
    }
  }
  // One pixel past the coarsest crop's reach fails (the check itself guards the reads).
  const double reach = 0.5 * (PatchPyramid::kCrop - 1) * (1 << (PatchPyramid::kLevels - 1));
  PatchPyramid pyr;
  EXPECT_FALSE(extractPatchPyramid(im, Vec2(reach - 1.0, 0.5 * kH), pyr));
  EXPECT_FALSE(extractPatchPyramid(im, Vec2(0.5 * kW, kH - reach), pyr));
}

TEST(VisualScores, ShiTomasiAndNccMatchBruteForce) {
  const Image im = noiseImage(kW, kH, 11);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(40.0, kW - 41.0), uy(40.0, kH - 41.0);
  for (int trial = 0; trial < 10; ++trial) {
    const Vec2 px(ux(rng), uy(rng));
    const int cx = int(std::lround(px.x())), cy = int(std::lround(px.y()));
    Eigen::Matrix2d m = Eigen::Matrix2d::Zero();
    for (int y = cy - 4; y < cy + 4; ++y) {
      for (int x = cx - 4; x < cx + 4; ++x) {
        const Eigen::Vector2d g(0.5 * (pixelAt(im, x + 1, y) - pixelAt(im, x - 1, y)),
                                0.5 * (pixelAt(im, x, y + 1) - pixelAt(im, x, y - 1)));
        m += g * g.transpose() / 64.0;
      }
    }
    const double expected = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(m).eigenvalues()(0);
    EXPECT_NEAR(shiTomasiScore(im, px), expected, 1e-9 * std::max(1.0, expected));
  }
  // A straight edge has one zero eigenvalue; a flat patch scores 0.
  const Image edge = makeImage(kW, kH, [](double x, double) { return x < 300 ? 50.0 : 200.0; });
  EXPECT_NEAR(shiTomasiScore(edge, Vec2(300, 200)), 0.0, 1e-9);
  EXPECT_NEAR(shiTomasiScore(makeImage(kW, kH, [](double, double) { return 90.0; }), Vec2(100, 100)), 0.0, 1e-12);

  PatchValues a{}, b{}, c{}, flat{};
  std::uniform_real_distribution<float> v(0.f, 255.f);
  for (std::size_t i = 0; i < a.size(); ++i) {
    a[i] = v(rng);
    b[i] = 2.f * a[i] + 5.f;  // affine brightness change
    c[i] = -a[i];
    flat[i] = 7.f;
  }
  EXPECT_NEAR(ncc(a, b), 1.0, 1e-6);
  EXPECT_NEAR(ncc(a, c), -1.0, 1e-6);
  EXPECT_EQ(ncc(a, flat), 0.0);
}

TEST(VisualCreation, ShiTomasiPicksTexturedCandidatePerFreeCell) {
  const auto cam = pinhole();
  // Flat left of x = 315, textured right of it.
  const Image noise = noiseImage(kW, kH, 21);
  const Image im = makeImage(kW, kH, [&](double x, double y) { return x < 315 ? 100.0 : pixelAt(noise, int(x), int(y)); });
  VisualMap map;
  const ImageGrid grid = selectionGrid(*cam, map.config().grid_cell_px);
  const Pose T_wc = Pose::Identity();
  // Cell [300, 330) x [240, 270): one flat and one textured candidate; cell [60, 90) x [60, 90) only a flat one.
  const Vec2 flat_px(305.0, 250.0), textured_px(322.0, 252.0), flat_only_px(70.0, 70.0);
  ASSERT_EQ(grid.cellOf(flat_px), grid.cellOf(textured_px));
  std::vector<NewPointCandidate> cands(3);
  cands[0].p_world = pointAtPixel(T_wc, flat_px, 4.0);
  cands[1].p_world = pointAtPixel(T_wc, textured_px, 4.2);
  cands[2].p_world = pointAtPixel(T_wc, flat_only_px, 4.0);
  for (auto& c : cands) {
    c.normal_world = Vec3(0, 0, 1);  // facing away: must be flipped
    c.cov_world = 1e-4 * Mat3::Identity();
  }
  EXPECT_EQ(map.addPoints(im, *cam, T_wc, 1.f, 1000, cands, {}), 1);
  ASSERT_EQ(map.size(), 1u);
  map.forEach([&](const VisualPoint& p) {
    EXPECT_LT((p.p_world - cands[1].p_world).norm(), 1e-12);
    EXPECT_LT((p.normal - Vec3(0, 0, -1)).norm(), 1e-12);
    ASSERT_EQ(p.obs.size(), 1u);
    EXPECT_EQ(p.reference, 0);
    EXPECT_LT((p.obs[0].px - textured_px).norm(), 1e-6);
    PatchPyramid direct;
    ASSERT_TRUE(extractPatchPyramid(im, p.obs[0].px, direct));
    EXPECT_EQ(direct.values, p.obs[0].patch.values);
  });
  // The same candidates with that cell occupied: nothing new.
  std::vector<bool> occupied(std::size_t(grid.size()), false);
  occupied[std::size_t(grid.cellOf(textured_px))] = true;
  EXPECT_EQ(map.addPoints(im, *cam, T_wc, 1.f, 2000, cands, occupied), 0);
  EXPECT_THROW(map.addPoints(im, *cam, T_wc, 1.f, 2000, cands, std::vector<bool>(3, false)), std::invalid_argument);
}

TEST(VisualCreation, RejectsCandidatesBehindOrTooCloseAndOutsideBorder) {
  const auto cam = pinhole();
  const Image im = noiseImage(kW, kH, 4);
  VisualMap map;
  const Pose T_wc = Pose::Identity();
  std::vector<NewPointCandidate> cands(4);
  // Behind: (-x, -y, -z) of a point that projects inside, i.e. the mirror image a naive projection
  // (u = fx x / z + cx) would place at the same pixel.
  cands[0].p_world = -pointAtPixel(T_wc, Vec2(200, 200), 3.0);
  cands[1].p_world = pointAtPixel(T_wc, Vec2(400, 300), 0.05);  // in front but closer than min_depth_m
  cands[2].p_world = pointAtPixel(T_wc, Vec2(10, 200), 3.0);    // inside the image, outside the border
  cands[3].p_world = pointAtPixel(T_wc, Vec2(500, 100), 3.0);   // valid
  EXPECT_EQ(map.addPoints(im, *cam, T_wc, 1.f, 0, cands, {}), 1);
  map.forEach([&](const VisualPoint& p) { EXPECT_LT((p.p_world - cands[3].p_world).norm(), 1e-12); });
  // The in-front check also holds under a moved camera.
  const Pose T_moved = Pose(Eigen::AngleAxisd(2.5, Vec3(0.3, 1.0, -0.2).normalized())) * Pose(Eigen::Translation3d(4, -1, 2));
  std::vector<NewPointCandidate> behind(1);
  behind[0].p_world = T_moved * Vec3(0.5, 0.2, -3.0);
  EXPECT_EQ(map.addPoints(im, *cam, T_moved, 1.f, 0, behind, {}), 0);
  Image wrong = noiseImage(kW / 2, kH / 2, 1);
  EXPECT_THROW(map.addPoints(wrong, *cam, T_wc, 1.f, 0, cands, {}), std::invalid_argument);

  // A wide fisheye model projects points behind the image plane inside the image (theta > 90 deg):
  // neither creation nor retrieval may take them.
  CameraConfig fc = pinholeConfig();
  fc.model = CameraKind::Equidistant;
  fc.fx = fc.fy = 60.0;
  const auto fisheye = CameraModel::create(fc);
  const Vec3 behind_cam(0.5, 0.2, -3.0);
  Vec2 px;
  ASSERT_TRUE(fisheye->project(behind_cam, px));
  ASSERT_TRUE(fisheye->inImage(px, map.config().border_px)) << px.transpose();
  VisualMap fmap;
  std::vector<NewPointCandidate> fc_cands(2);
  fc_cands[0].p_world = behind_cam;
  fc_cands[1].p_world = Vec3(-0.5, 0.2, 3.0);  // its mirror in front
  EXPECT_EQ(fmap.addPoints(im, *fisheye, T_wc, 1.f, 0, fc_cands, {}), 1);
  fmap.forEach([&](const VisualPoint& p) { EXPECT_GT(p.p_world.z(), 0.0); });
  fmap.insert(simplePoint(1000, behind_cam));
  const auto seen = fmap.retrieve(*fisheye, T_wc, {behind_cam, fc_cands[1].p_world}).points;
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_NE(seen[0]->id, 1000);
}

namespace {

struct Expected {
  std::int64_t id;
  Vec2 px;
};

// Brute force over every point of the map (docs/algorithms.md 4.2 as specified in VisualMap::retrieve).
std::map<int, Expected> bruteForceInView(const VisualMap& map, const CameraModel& cam, const Pose& T_wc,
                                         const std::vector<Vec3>& scan) {
  const VisualMapConfig& cfg = map.config();
  const ImageGrid grid = selectionGrid(cam, map.config().grid_cell_px);
  const Pose T_cw = T_wc.inverse();
  auto key = [&](const Vec3& p) {
    return std::array<long, 3>{long(std::floor(p.x() / cfg.voxel_size_m)), long(std::floor(p.y() / cfg.voxel_size_m)),
                               long(std::floor(p.z() / cfg.voxel_size_m))};
  };
  std::map<int, std::tuple<double, std::int64_t, Vec2>> best;
  map.forEach([&](const VisualPoint& p) {
    if (p.referenceObs() == nullptr) return;
    bool in_scan_voxel = false;
    for (const Vec3& s : scan) in_scan_voxel = in_scan_voxel || key(s) == key(p.p_world);
    if (!in_scan_voxel) return;
    const Vec3 pc = T_cw * p.p_world;
    Vec2 px;
    if (pc.z() < cfg.min_depth_m || !cam.project(pc, px) || !cam.inImage(px, cfg.border_px)) return;
    const int cell = int(px.y() / cfg.grid_cell_px) * grid.cols + int(px.x() / cfg.grid_cell_px);
    auto it = best.find(cell);
    if (it == best.end() || pc.z() < std::get<0>(it->second)) best[cell] = {pc.z(), p.id, px};
  });
  std::map<int, Expected> out;
  for (const auto& kv : best) {
    const double z = std::get<0>(kv.second);
    const Vec2 px = std::get<2>(kv.second);
    bool occluded = false;
    for (const Vec3& s : scan) {
      const Vec3 sc = T_cw * s;
      Vec2 spx;
      if (!(sc.z() > 0.0) || !cam.project(sc, spx)) continue;
      if (std::abs(std::lround(spx.x()) - std::lround(px.x())) <= cfg.occlusion_window_px &&
          std::abs(std::lround(spx.y()) - std::lround(px.y())) <= cfg.occlusion_window_px &&
          sc.z() < z - cfg.occlusion_depth_m)
        occluded = true;
    }
    if (!occluded) out[kv.first] = {std::get<1>(kv.second), px};
  }
  return out;
}

}  // namespace

TEST(VisualRetrieval, MatchesBruteForceProjectionOfAllPoints) {
  const auto cam = pinhole();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ux(-8, 8), uy(-6, 6), uz(-2, 15), jitter(-0.03, 0.03);
  VisualMap map;
  const ImageGrid grid = selectionGrid(*cam, map.config().grid_cell_px);
  const Pose T_wc = Pose(Eigen::Translation3d(-1.3, 0.7, -2.2)) * Pose(Eigen::AngleAxisd(0.4, Vec3(0.2, 1, 0.1).normalized()));
  std::vector<Vec3> scan;
  for (int i = 0; i < 1500; ++i) {
    const Vec3 p = T_wc * Vec3(ux(rng), uy(rng), uz(rng));  // world coordinates of both signs
    ASSERT_TRUE(map.insert(simplePoint(i + 1, p, i % 10 != 0)));  // every tenth has no reference
    if (i % 10 < 7) scan.push_back(p + Vec3(jitter(rng), jitter(rng), jitter(rng)));
  }
  for (int i = 0; i < 800; ++i) scan.push_back(T_wc * Vec3(ux(rng), uy(rng), uz(rng)));
  const VisualRetrieval r = map.retrieve(*cam, T_wc, scan);
  const std::vector<VisualPoint*>& got = r.points;
  const std::vector<Vec2>& pixels = r.pixels;
  const std::map<int, Expected> expected = bruteForceInView(map, *cam, T_wc, scan);
  ASSERT_EQ(got.size(), pixels.size());
  ASSERT_EQ(got.size(), expected.size());
  EXPECT_GT(got.size(), 50u);
  EXPECT_GT(r.stats.occluded, 0u);
  EXPECT_EQ(r.stats.selected, got.size());
  EXPECT_EQ(r.grid.size(), grid.size());
  EXPECT_EQ(r.longterm, 0u);
  std::size_t k = 0;
  for (const auto& kv : expected) {  // both ordered by cell
    EXPECT_EQ(got[k]->id, kv.second.id);
    EXPECT_LT((pixels[k] - kv.second.px).norm(), 1e-9);
    EXPECT_EQ(grid.cellOf(pixels[k]), kv.first);
    EXPECT_TRUE(r.occupied[std::size_t(kv.first)]);
    ++k;
  }
  EXPECT_EQ(std::count(r.occupied.begin(), r.occupied.end(), true), long(expected.size()));
}

TEST(VisualRetrieval, FloorKeysNearNegativeVoxelBorders) {
  // Voxels [-0.5, 0) and [0, 0.5) meet at 0: a scan point must select exactly its own voxel.
  const auto cam = pinhole();
  VisualMap map;
  map.insert(simplePoint(1, Vec3(-0.05, -0.3, 3.1)));  // voxel (-1, -1, 6)
  map.insert(simplePoint(2, Vec3(0.45, 0.3, 3.1)));    // voxel (0, 0, 6)
  EXPECT_EQ(map.keyOf(Vec3(-0.05, -0.3, 3.1)).x, -1);
  auto ids = [&](const std::vector<Vec3>& scan) {
    std::set<std::int64_t> s;
    for (VisualPoint* p : map.retrieve(*cam, Pose::Identity(), scan).points) s.insert(p->id);
    return s;
  };
  EXPECT_EQ(ids({Vec3(-0.45, -0.05, 3.4)}), (std::set<std::int64_t>{1}));
  EXPECT_EQ(ids({Vec3(0.01, 0.01, 3.01)}), (std::set<std::int64_t>{2}));
  EXPECT_TRUE(ids({Vec3(-0.55, -0.3, 3.1)}).empty());  // neighbour voxel (-2, -1, 6)
}

TEST(VisualRetrieval, OcclusionBySyntheticDepth) {
  const auto cam = pinhole();
  const Pose T_wc = Pose::Identity();
  const Vec2 px(320.0, 240.0);
  const Vec3 p = pointAtPixel(T_wc, px, 8.0);  // on a wall at 8 m
  auto run = [&](const std::vector<Vec3>& occluders) {
    VisualMap map;
    map.insert(simplePoint(7, p));
    std::vector<Vec3> scan = {p};  // the wall point selects the voxel
    scan.insert(scan.end(), occluders.begin(), occluders.end());
    const VisualRetrieval r = map.retrieve(*cam, T_wc, scan);
    const std::size_t n = r.points.size();
    EXPECT_EQ(r.occupied[std::size_t(r.grid.cellOf(px))], n == 1);
    return n;
  };
  EXPECT_EQ(run({}), 1u);
  EXPECT_EQ(run({pointAtPixel(T_wc, px + Vec2(3, -4), 3.0)}), 0u);  // closer by 5 m within +-4 px
  EXPECT_EQ(run({pointAtPixel(T_wc, px + Vec2(6, 0), 3.0)}), 1u);   // outside the window
  EXPECT_EQ(run({pointAtPixel(T_wc, px + Vec2(1, 1), 7.7)}), 1u);   // closer by 0.3 m only
  EXPECT_EQ(run({pointAtPixel(T_wc, px + Vec2(1, 1), 9.5)}), 1u);   // behind the point
}

TEST(VisualRetrieval, TimingFor1000PointsInView) {
  const auto cam = pinhole();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(-1, 1), uy(-1, 1), uz(2, 30);
  VisualMap map;
  const Pose T_wc = Pose(Eigen::Translation3d(0.5, -0.2, 1.0));
  std::vector<Vec3> scan;
  for (int i = 0; i < 1000; ++i) {
    const double z = uz(rng);
    const Vec3 p = T_wc * Vec3(ux(rng) * 0.8 * z * 320 / 400, uy(rng) * 0.8 * z * 240 / 400, z);
    map.insert(simplePoint(i + 1, p));
    scan.push_back(p);
  }
  for (int i = 0; i < 9000; ++i) {  // a downsampled scan of ~10k points, mostly where the points are
    const double z = uz(rng);
    scan.push_back(T_wc * Vec3(ux(rng) * z, uy(rng) * z, z));
  }
  std::vector<double> ms;
  std::size_t selected = 0;
  VisualRetrievalStats stats;
  for (int rep = 0; rep < 20; ++rep) {
    Stopwatch sw;
    const VisualRetrieval r = map.retrieve(*cam, T_wc, scan);
    ms.push_back(sw.elapsedMs());
    selected = r.points.size();
    stats = r.stats;
  }
  const SampleSummary s = summarize(ms);
  std::cout << "[figure] retrieve: 1000 map points, " << scan.size() << " scan points, "
            << stats.visual_voxels << " visual voxels searched, " << stats.in_image
            << " in image, " << selected << " selected: median " << s.median << " ms, max " << s.max << " ms\n";
  EXPECT_GT(selected, 100u);
}

// The grid sampler returns sampleBilinear's values bit for bit, NaN exactly where sampleBilinear refuses
// (outside [0, w-1] x [0, h-1], the last column and row included, non-finite coordinates).
TEST(VisualPatch, GridSamplerIsBitIdenticalToSampleBilinear) {
  std::mt19937 rng(7);
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{40, 30}, {2, 2}, {1, 5}, {64, 3}}) {
    Image img;
    img.width = w;
    img.height = h;
    img.row_stride = w;
    img.data.resize(std::size_t(w * h));
    for (auto& b : img.data) b = static_cast<std::uint8_t>(rng() % 256);
    std::uniform_real_distribution<double> ux(-3.0, w + 2.0), uy(-3.0, h + 2.0);
    for (int trial = 0; trial < 50; ++trial) {
      double xs[12], ys[10];
      for (double& x : xs) x = ux(rng);
      for (double& y : ys) y = uy(rng);
      xs[0] = w - 1, xs[1] = 0.0, ys[0] = h - 1, ys[1] = 0.0;  // the edges themselves
      xs[2] = std::numeric_limits<double>::quiet_NaN();
      float out[12 * 10];
      sampleBilinearGrid(img, xs, 12, ys, 10, out);
      for (int j = 0; j < 10; ++j)
        for (int i = 0; i < 12; ++i) {
          float v = 0;
          const bool ok = sampleBilinear(img, xs[i], ys[j], v);
          if (!ok) {
            EXPECT_TRUE(std::isnan(out[j * 12 + i])) << w << "x" << h << " at " << xs[i] << ", " << ys[j];
          } else {
            EXPECT_EQ(out[j * 12 + i], v) << w << "x" << h << " at " << xs[i] << ", " << ys[j];
          }
        }
    }
  }
}
