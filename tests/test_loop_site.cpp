// A map to come back to (libs/loop site_map, relocaliser): a site map saved from a loop closer and read
// back (keyframes, descriptors, points; tiles read lazily within a budget; damaged files refused naming
// the file), and localising in it from the simulator's revisit block: a second run in the same world
// (world.seed) from another start (trajectory.start_m) with its own odometry frame and a drifting
// odometry, against the ground truth without any alignment (the map is made in the world frame).
// livo-test-deps: livo_sim
// livo-test-whole
#include "livo/loop/loop_closer.hpp"
#include "livo/loop/map_frame.hpp"
#include "livo/loop/relocaliser.hpp"
#include "livo/loop/site_map.hpp"
#include "loop_test_util.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace livo {
namespace {

namespace fs = std::filesystem;

LoopConfig defaults(const sim::SimScenario& sc) {
  const ConfigFile f = ConfigFile::parse("loop: {}\n", "rig.yaml");
  LoopConfig cfg;
  cfg.load(f.root().section("loop"), sc.lidar.max_range_m, sc.lidar.range_noise_m, sc.lidar.beam_noise_deg);
  return cfg;
}

std::string tempDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("livo_test_site_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

/// A loop closer fed the revisit scenario's true poses and scans for `duration_s` (its map frame is the
/// world frame: no drift, so no correction).
struct TruthMap {
  sim::SimScenario sc;
  LoopCloser closer;
  explicit TruthMap(double duration_s) : sc(test::revisitScenario()), closer(defaults(sc)) {
    sc.duration_s = duration_s;
    const sim::Simulator s(sc);
    const auto scans = static_cast<std::int64_t>(duration_s * sc.lidar.rate_hz) - 1;
    for (std::int64_t j = 0; j < scans; ++j)
      closer.add(s.lidarUtime(j), s.T_world_imu(s.lidarUtime(j)), [&] { return test::worldScan(s, j); });
    closer.finish();
  }
};

const TruthMap& firstLap() {
  static const TruthMap m(48.0);  // 4 s of start and one 41 s lap of the 340 m block
  return m;
}

struct SecondRun {
  int frames = 0, first_localised = -1, left = 0, back = 0;
  double mean_m = 0.0, max_m = 0.0;
  std::size_t posed = 0, tile_reads = 0, tiles_held = 0;
};

/// The second run: same world (world.seed 11), other noise (seed 12), from 150 m along the path, for
/// `duration_s`; its odometry starts in its own frame (turned 30 deg, 5 m off) and drifts 0.5 % and
/// 0.004 deg a scan. Map-frame poses of the frames from the first localised one on, against the truth.
SecondRun secondRun(const std::string& site_dir, double duration_s, double budget_mb) {
  sim::SimScenario sc = test::revisitScenario();
  sc.seed = 12;
  sc.world.seed = 11;
  sc.trajectory.start_m = 150.0;
  sc.duration_s = duration_s;
  const sim::Simulator s(sc);
  LoopConfig cfg = defaults(sc);
  SiteMap site(site_dir, budget_mb, cfg.descriptor);
  Relocaliser reloc(cfg, site);
  Pose frame = Pose::Identity();
  frame.linear() = Eigen::AngleAxisd(M_PI / 6, Vec3::UnitZ()).toRotationMatrix();
  frame.translation() = Vec3(5, -3, 0.2);
  Pose odom = frame * s.T_world_imu(s.lidarUtime(0)), prev_truth = s.T_world_imu(s.lidarUtime(0));
  std::vector<std::pair<Pose, Pose>> poses;  // odometry, truth
  std::vector<Utime> times;
  SecondRun out;
  const auto scans = static_cast<std::int64_t>(duration_s * sc.lidar.rate_hz) - 1;
  for (std::int64_t j = 0; j < scans; ++j) {
    const Pose truth = s.T_world_imu(s.lidarUtime(j));
    if (j > 0) odom = odom * test::driftedStep(prev_truth, truth);
    prev_truth = truth;
    const Pose to_odom = odom * truth.inverse();
    const RelocaliseStep st = reloc.add(s.lidarUtime(j), odom, [&] {
      std::vector<Vec3> pts = test::worldScan(s, j);
      for (Vec3& p : pts) p = to_odom * p;
      return pts;
    });
    if (st.localised_now) out.first_localised = int(j);
    out.left += st.left_map;
    out.back += st.back_in_map;
    poses.emplace_back(odom, truth);
    times.push_back(s.lidarUtime(j));
  }
  MapFrameTrajectory map;
  EXPECT_EQ(map.apply(reloc.anchors()), "");
  double sum = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto T = map.toMap(times[i], poses[i].first);
    if (!T) continue;
    const double e = (T->translation() - poses[i].second.translation()).norm();
    sum += e;
    out.max_m = std::max(out.max_m, e);
    ++out.posed;
  }
  out.frames = int(poses.size());
  out.mean_m = out.posed ? sum / double(out.posed) : 1e9;
  out.tile_reads = site.tileReads();
  out.tiles_held = site.tilesHeld();
  std::printf("second run %.0f s: %d frames, localised at frame %d, %zu frames in the map frame, error mean %.3f m "
              "max %.3f m; left the map %d, back %d; %zu tile reads, %zu held\n",
              duration_s, out.frames, out.first_localised, out.posed, out.mean_m, out.max_m, out.left, out.back,
              out.tile_reads, out.tiles_held);
  return out;
}

TEST(SiteMap, SavedKeyframesReadBackWithTheirDescriptorsAndPoints) {
  const TruthMap& m = firstLap();
  const std::string dir = tempDir("roundtrip");
  const LoopConfig cfg = defaults(m.sc);
  saveSiteMap(dir, m.closer, cfg.descriptor, 50.0);
  SiteMap site(dir, 0.0, cfg.descriptor);
  ASSERT_EQ(site.size(), m.closer.graph().size());
  std::size_t tiles = 0;
  for (const auto& e : fs::directory_iterator(dir + "/tiles")) tiles += e.path().extension() == ".bin";
  std::printf("%zu keyframes in %zu tiles of 50 m; index %zu bytes in memory\n", site.size(), tiles, site.indexBytes());
  EXPECT_GE(tiles, 4u) << "a 120 m x 50 m block in 50 m tiles";
  for (int i = 0; i < int(site.size()); ++i) {
    const SiteKeyframe& k = site.keyframe(i);
    EXPECT_EQ(k.utime, m.closer.places().entry(i).utime);
    EXPECT_LT((k.T_map.translation() - m.closer.graph().mapPose(i).translation()).norm(), 1e-9);
    EXPECT_LT((k.T_map.linear() - m.closer.graph().mapPose(i).linear()).norm(), 1e-9);
    EXPECT_EQ(k.descriptor.cells(), m.closer.places().entry(i).descriptor.cells());
    EXPECT_EQ(k.descriptor.ringKeyDistance(m.closer.places().entry(i).descriptor), 0.0);
    const std::vector<Vec3> a = site.points(i), b = m.closer.keyframePoints(i).unpack();
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t j = 0; j < a.size(); j += 97) EXPECT_EQ(a[j], b[j]);
  }
  EXPECT_EQ(site.tileReads(), tiles) << "each tile read once without a budget";

  // A budget of one tile: every change of tile reads again (here: alternating between opposite sides of
  // the block), the points stay the same.
  SiteMap small(dir, 1e-6, cfg.descriptor);
  const int n = int(small.size());
  for (int i = 0; i < n / 2; i += 7) {
    EXPECT_EQ(small.points(i), site.points(i));
    EXPECT_EQ(small.points(i + n / 2), site.points(i + n / 2));
  }
  EXPECT_EQ(small.tilesHeld(), 1u);
  EXPECT_GT(small.tileReads(), tiles);
}

TEST(SiteMap, DamagedOrForeignFilesAreRefusedNamingTheFile) {
  const TruthMap& m = firstLap();
  const LoopConfig cfg = defaults(m.sc);
  const std::string dir = tempDir("damaged");
  saveSiteMap(dir, m.closer, cfg.descriptor, 100.0);
  auto error = [&](const std::string& d, const PlaceDescriptorConfig& desc) -> std::string {
    try {
      SiteMap s(d, 0.0, desc);
      for (int i = 0; i < int(s.size()); ++i) s.points(i);
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error(dir, cfg.descriptor), "");
  EXPECT_NE(error(dir + "/nowhere", cfg.descriptor).find("nowhere/site.bin: cannot open"), std::string::npos);
  PlaceDescriptorConfig other = cfg.descriptor;
  other.sectors = 90;
  EXPECT_NE(error(dir, other).find("made with a place descriptor of 20 x 60"), std::string::npos) << error(dir, other);

  const std::string bad = tempDir("damaged_copy");
  fs::copy(dir, bad, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  fs::resize_file(bad + "/site.bin", fs::file_size(bad + "/site.bin") - 10);
  EXPECT_NE(error(bad, cfg.descriptor).find("site.bin: "), std::string::npos) << error(bad, cfg.descriptor);
  std::ofstream(bad + "/site.bin", std::ios::trunc) << "not a site map at all";
  EXPECT_NE(error(bad, cfg.descriptor).find("bad magic"), std::string::npos) << error(bad, cfg.descriptor);

  fs::copy(dir + "/site.bin", bad + "/site.bin", fs::copy_options::overwrite_existing);
  for (const auto& e : fs::directory_iterator(bad + "/tiles")) {
    fs::resize_file(e.path(), 8 + 6 * ((fs::file_size(e.path()) - 8) / 12));  // a tile cut short (whole points)
    break;
  }
  EXPECT_NE(error(bad, cfg.descriptor).find("points, keyframe"), std::string::npos) << error(bad, cfg.descriptor);
}

// The whole second run inside the map: localised within a second, every frame after in the map frame
// within centimetres of the truth, with no alignment.
TEST(Relocaliser, LocalisesASecondRunFromAnotherStartWithoutAnInitialPose) {
  const TruthMap& m = firstLap();
  const std::string dir = tempDir("reloc");
  saveSiteMap(dir, m.closer, defaults(m.sc).descriptor, 100.0);
  const SecondRun r = secondRun(dir, 30.0, 64.0);
  // 2026-12-06: localised at frame 5 (two agreeing tries 0.5 s apart, at rest), error mean 0.015 m,
  // max 0.030 m over 294 frames (re-anchoring on every match: 0.005 / 0.017 m with this odometry's
  // strong drift, but a match that slid along the street then moved livo-run's second run by 14 cm; the
  // fused anchors follow the drift with a lag). Bounds about twice the figures.
  ASSERT_GE(r.first_localised, 0);
  EXPECT_LE(r.first_localised, 10) << "within a second of 10 Hz frames";
  EXPECT_LT(r.mean_m, 0.03);
  EXPECT_LT(r.max_m, 0.06);
  EXPECT_EQ(r.left, 0);
}

// A map of half the block: the second run leaves it (says so), runs on the odometry, and is back in it
// when it reaches the mapped half again.
TEST(Relocaliser, LeavesAPartialMapAndComesBackIntoIt) {
  const TruthMap half(25.0);
  const std::string dir = tempDir("half");
  saveSiteMap(dir, half.closer, defaults(half.sc).descriptor, 25.0);
  const SecondRun r = secondRun(dir, 40.0, 1.0);
  ASSERT_GE(r.first_localised, 0);
  EXPECT_EQ(r.left, 1);
  EXPECT_EQ(r.back, 1);
  // 2026-12-06: error mean 0.203 m over the run (the drift of 0.5 % and 0.004 deg a scan outside the
  // map included), max 0.538 m. Bounds about twice the figures. A 1 MB tile budget holds one or two
  // 25 m tiles.
  EXPECT_LT(r.mean_m, 0.35);
  EXPECT_LT(r.max_m, 1.0);
  EXPECT_LE(r.tiles_held, 2u);
}

}  // namespace
}  // namespace livo
