// What livo-viewer accumulates and how it colours it (libs/viewer): the voxel map against a
// brute-force voxel mean, least-recently-seen eviction at the point bound, the colour maps (none
// reaches the trajectory's magenta), the scene's clipping above the trajectory, its colour modes and
// frame rate, the trajectory's bound, and the overlay's figures.
#include "livo/viewer/colour.hpp"
#include "livo/viewer/map_accumulator.hpp"
#include "livo/viewer/scene.hpp"
#include "livo/viewer/trajectory_track.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

using namespace livo;
using namespace livo::viewer;

namespace {

std::vector<Eigen::Vector3f> randomPoints(std::size_t n, float extent, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-extent, extent);
  std::vector<Eigen::Vector3f> pts(n);
  for (auto& p : pts) p = Eigen::Vector3f(u(rng), u(rng), u(rng));
  return pts;
}

PoseInput poseAt(double t_s, const Vec3& p, double yaw = 0.0) {
  PoseInput in;
  in.utime = fromSeconds(t_s);
  in.T_world_imu = Pose::Identity();
  in.T_world_imu.linear() = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
  in.T_world_imu.translation() = p;
  return in;
}

}  // namespace

TEST(ViewerMap, OnePointPerVoxelAtTheMeanOfItsPoints) {
  const double voxel = 0.25;
  const auto pts = randomPoints(5000, 2.0f, 1);
  std::vector<float> intensity(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) intensity[i] = float(i % 17);
  MapAccumulator map({voxel, 1'000'000});
  map.add(pts, intensity, {});
  // Oracle: group by floor(p / voxel) in a std::map and average.
  std::map<std::tuple<int, int, int>, std::tuple<Eigen::Vector3d, double, int>> ref;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto key = std::make_tuple(int(std::floor(pts[i].x() / voxel)), int(std::floor(pts[i].y() / voxel)),
                                     int(std::floor(pts[i].z() / voxel)));
    auto& [sum, isum, n] = ref[key];
    if (n == 0) sum.setZero();
    sum += pts[i].cast<double>();
    isum += intensity[i];
    ++n;
  }
  ASSERT_EQ(map.size(), ref.size());
  std::size_t checked = 0;
  map.forEach([&](const MapPoint& m) {
    // The voxel of a mean lies in the voxel of its points.
    const auto key = std::make_tuple(int(std::floor(m.p.x() / voxel)), int(std::floor(m.p.y() / voxel)),
                                     int(std::floor(m.p.z() / voxel)));
    const auto it = ref.find(key);
    ASSERT_NE(it, ref.end());
    const auto& [sum, isum, n] = it->second;
    EXPECT_EQ(int(m.n), n);
    EXPECT_LT((m.p.cast<double>() - sum / n).norm(), 1e-5);
    EXPECT_NEAR(m.intensity, isum / n, 1e-3);
    EXPECT_EQ(m.rgb, -1);
    ++checked;
  });
  EXPECT_EQ(checked, ref.size());
}

TEST(ViewerMap, BoundedByEvictingTheLeastRecentlySeenVoxels) {
  MapAccumulator map({1.0, 3});
  const auto at = [](float x) { return std::vector<Eigen::Vector3f>{Eigen::Vector3f(x + 0.5f, 0.5f, 0.5f)}; };
  map.add(at(0), {}, {});
  map.add(at(1), {}, {});
  map.add(at(2), {}, {});
  map.add(at(0), {}, {});  // voxel 0 seen again: now voxel 1 is the least recent
  map.add(at(3), {}, {});  // evicts voxel 1
  EXPECT_EQ(map.size(), 3u);
  EXPECT_EQ(map.evicted(), 1u);
  std::vector<float> xs;
  map.forEach([&](const MapPoint& m) { xs.push_back(std::floor(m.p.x())); });
  EXPECT_EQ(xs, (std::vector<float>{2, 0, 3}));  // least to most recently seen
}

TEST(ViewerMap, LatestColourNonFiniteSkippedAndSizesChecked) {
  MapAccumulator map({1.0, 100});
  const Eigen::Vector3f p(0.5f, 0.5f, 0.5f);
  const float nan = std::nanf("");
  map.add({p, p, Eigen::Vector3f(nan, 0, 0)}, {1.f, 3.f, 0.f}, {0x102030, -1, 0x405060});
  map.add({p}, {}, {0xABCDEF});
  EXPECT_EQ(map.size(), 1u);
  EXPECT_EQ(map.skipped(), 1u);
  map.forEach([&](const MapPoint& m) {
    EXPECT_EQ(m.rgb, 0xABCDEF);       // the latest camera colour
    EXPECT_NEAR(m.intensity, 4.f / 3, 1e-6);  // (1 + 3 + 0) / 3: a point without intensity counts 0
  });
  const auto before = map.version();
  map.add({Eigen::Vector3f(nan, nan, nan)}, {}, {});
  EXPECT_EQ(map.version(), before) << "nothing added, nothing to redraw";
  EXPECT_THROW(map.add({p, p}, {1.f}, {}), std::invalid_argument);
  EXPECT_THROW(map.add({p}, {}, {1, 2}), std::invalid_argument);
  EXPECT_THROW(MapAccumulator({0.0, 10}), std::invalid_argument);
  EXPECT_THROW(MapAccumulator({0.1, 0}), std::invalid_argument);
  map.clear();
  EXPECT_EQ(map.size(), 0u);
}

TEST(ViewerColour, RampsAreMonotoneAndNeverMagenta) {
  EXPECT_EQ(heightColour(0.0), (Rgb{30, 60, 230}));
  EXPECT_EQ(heightColour(1.0), (Rgb{220, 30, 0}));
  EXPECT_EQ(heightColour(-5.0), heightColour(0.0));
  EXPECT_EQ(heightColour(std::nan("")), heightColour(0.0));
  EXPECT_EQ(intensityColour(0.0), (Rgb{40, 40, 40}));
  EXPECT_EQ(intensityColour(2.0), (Rgb{255, 255, 255}));
  int prev_gray = -1;
  for (int i = 0; i <= 1000; ++i) {
    const double t = i / 1000.0;
    const Rgb h = heightColour(t);
    // Far from the trajectory's (255, 0, 255) and the frustum's colour: the screenshot test finds the
    // trajectory by its exact colour.
    const int d = std::abs(h.r - 255) + std::abs(h.g - 0) + std::abs(h.b - 255);
    EXPECT_GT(d, 200) << t;
    EXPECT_FALSE(h.r > 128 && h.b >= 40) << t;
    const Rgb g = intensityColour(t);
    EXPECT_GE(g.r, prev_gray);
    prev_gray = g.r;
  }
  EXPECT_EQ(imageColour(0x0A0B0C), (Rgb{10, 11, 12}));
  EXPECT_EQ(imageColour(-1), kUnseenColour);
  ColourMode m = ColourMode::kHeight;
  EXPECT_TRUE(parseColourMode("image", m));
  EXPECT_EQ(m, ColourMode::kImage);
  EXPECT_FALSE(parseColourMode("rainbow", m));
  EXPECT_EQ(nextColourMode(ColourMode::kHeight, true), ColourMode::kIntensity);
  EXPECT_EQ(nextColourMode(ColourMode::kHeight, false), ColourMode::kImage);
  EXPECT_EQ(nextColourMode(ColourMode::kImage, true), ColourMode::kHeight);
}

TEST(ViewerTrajectory, KeepsOrderAndStaysBoundedOverTheWholePath) {
  TrajectoryTrack track(100);
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(track.add(poseAt(i * 0.1, Vec3(i, 0, 0))));
  EXPECT_FALSE(track.add(poseAt(5.0, Vec3::Zero())));
  EXPECT_EQ(track.outOfOrder(), 1u);
  EXPECT_LE(track.poses().size(), 100u);
  EXPECT_EQ(track.added(), 1000u);
  EXPECT_EQ(track.poses().front().utime, 0) << "the start stays";
  EXPECT_EQ(track.last().utime, fromSeconds(99.9));
  for (std::size_t i = 1; i < track.poses().size(); ++i)
    EXPECT_LT(track.poses()[i - 1].utime, track.poses()[i].utime);
  EXPECT_DOUBLE_EQ(track.maxCorner().x(), 999.0);
  EXPECT_DOUBLE_EQ(track.minCorner().x(), 0.0);
  EXPECT_THROW(TrajectoryTrack(3), std::invalid_argument);
}

TEST(ViewerScene, ClipsAboveTheTrajectoryColoursByModeAndCountsFrames) {
  SceneConfig cfg;
  cfg.map = {0.1, 10'000};
  cfg.clip_above_m = 1.0;
  Scene scene(cfg);
  InboxBatch b;
  ScanInput scan;
  // A column of points from z = 0 to 4 m, with intensity = z and a colour on the lowest one.
  for (int i = 0; i < 40; ++i) {
    scan.points.emplace_back(0.05f, 0.05f, 0.05f + 0.1f * i);
    scan.intensity.push_back(0.1f * i);
    scan.rgb.push_back(i == 0 ? 0x00FF00 : -1);
  }
  b.scans.push_back(scan);
  for (int i = 0; i <= 20; ++i) b.poses.push_back(poseAt(i * 0.1, Vec3(0, 0, 1.5)));  // 10 Hz at 1.5 m
  b.drops.scans = 2;
  scene.apply(b);
  EXPECT_DOUBLE_EQ(scene.clipZ(), 2.5);
  EXPECT_NEAR(scene.rateHz(), 10.0, 1e-9);
  EXPECT_NEAR(scene.elapsedS(), 2.0, 1e-9);
  const ColouredPoints h = scene.mapPoints(ColourMode::kHeight);
  ASSERT_EQ(h.xyz.size(), 25u);  // z = 0.05 ... 2.45
  for (const auto& p : h.xyz) EXPECT_LE(p.z(), 2.5f);
  EXPECT_EQ(h.rgb.front(), heightColour(0.0));  // lowest drawn = bottom of the ramp
  EXPECT_EQ(h.rgb.back(), heightColour(1.0));
  const ColouredPoints img = scene.mapPoints(ColourMode::kImage);
  EXPECT_EQ(img.rgb.front(), (Rgb{0, 255, 0}));
  EXPECT_EQ(img.rgb.back(), kUnseenColour);
  const ColouredPoints in = scene.mapPoints(ColourMode::kIntensity);
  EXPECT_EQ(in.rgb.front(), intensityColour(0.0));
  EXPECT_EQ(scene.scanPoints().xyz.size(), 25u);
  EXPECT_EQ(scene.scanPoints().rgb.front(), kScanColour);
  EXPECT_EQ(scene.drops().scans, 2u);

  const std::string text = overlayText(scene.overlay("live", ViewMode::kTop, ColourMode::kImage));
  EXPECT_NE(text.find("frames 21"), std::string::npos) << text;
  EXPECT_NE(text.find("10.0 Hz"), std::string::npos) << text;
  EXPECT_NE(text.find("dropped: 2 scans"), std::string::npos) << text;
  EXPECT_NE(text.find("view top"), std::string::npos) << text;
  EXPECT_EQ(text.find("sigma_min"), std::string::npos) << "no frame statistics yet";

  InboxBatch b2;
  FrameStatsInput f;
  f.total_ms = 12.5f;
  f.sigma_min = 0.042f;
  f.degenerate = true;
  b2.frame_stats.push_back(f);
  b2.map_stats = MapStatsInput{0, 3 << 20, 512 << 20, 100, 50};
  scene.apply(b2);
  const std::string text2 = overlayText(scene.overlay("live", ViewMode::kFollow, ColourMode::kHeight));
  EXPECT_NE(text2.find("frame 12.5 ms"), std::string::npos) << text2;
  EXPECT_NE(text2.find("sigma_min 0.042   DEGENERATE"), std::string::npos) << text2;
  EXPECT_NE(text2.find("map server 3.0 MiB of 512 MiB cap"), std::string::npos) << text2;
  EXPECT_EQ(text2.find("LOST"), std::string::npos) << text2;
  InboxBatch b3;
  f.health = 3;
  f.health_reason = "matched 3 of 900 covered points (usually 0.93)";
  b3.frame_stats.push_back(f);
  scene.apply(b3);
  const std::string text3 = overlayText(scene.overlay("live", ViewMode::kFollow, ColourMode::kHeight));
  EXPECT_NE(text3.find("LOST (do not navigate on this pose): matched 3 of 900"), std::string::npos) << text3;

  scene.clear();
  EXPECT_EQ(scene.map().size(), 0u);
  EXPECT_TRUE(scene.track().empty());
  EXPECT_TRUE(std::isinf(scene.clipZ()));
  EXPECT_FALSE(scene.firstUtime());
}

TEST(ViewerScene, NoClippingWhenOff) {
  SceneConfig cfg;
  cfg.clip_above_m = 0.0;
  Scene scene(cfg);
  InboxBatch b;
  b.scans.push_back(ScanInput{0, {Eigen::Vector3f(0, 0, 100)}, {}, {}});
  b.poses.push_back(poseAt(0, Vec3::Zero()));
  scene.apply(b);
  EXPECT_EQ(scene.mapPoints(ColourMode::kHeight).xyz.size(), 1u);
}
