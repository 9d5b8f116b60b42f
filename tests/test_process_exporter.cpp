// The core of livo-exporter (libs/process ExporterNode, MapCloud, OccupancyMap) driven over memq://:
// trajectory.tum and frames.csv byte-equal to livo-run's (RunOutputs) and on disk per frame, the map
// section of stats.json from the newest map_stats_t, map.pcd coloured where the camera saw the points
// (read back with PCL; voxel centroids and colours against brute force), map.bt occupied at the
// points and free along the rays (read back with OctoMap), late / lost / reordered messages.
#include "livo/common/timing.hpp"
#include "livo/eval/tum.hpp"
#include "livo/io/run_outputs.hpp"
#include "livo/process/exporter_node.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/map_export.hpp"

#include "process_test_files.hpp"
#include "process_test_streams.hpp"

#include <octomap/OcTree.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <tuple>

using namespace livo;
using test::lines;
using test::readFile;
using test::tempDir;

// ---------------------------------------------------------------- ExporterNode

namespace {

/// Publishes the frames' messages on `lcm` (odometry, scan, stats, map stats) and drains.
void publishFrames(LcmNode& lcm, const std::vector<test::EstimatorFrame>& frames) {
  for (const auto& f : frames) {
    lcm.publish("LIVO_ODOMETRY", toMsg(f.odom));
    lcm.publish("LIVO_REGISTERED_SCAN", toMsg(f.scan));
    lcm.publish("LIVO_ESTIMATOR_STATS", toMsg(f.stats));
    if (f.has_map_stats) lcm.publish("LIVO_MAP_STATS", toMsg(f.map_stats));
    lcm.drain();
  }
}

FrameRecord recordOf(const test::EstimatorFrame& f) {
  FrameRecord r;
  r.utime = f.odom.utime;
  r.has_pose = !(f.odom.status & odometry_status::kInitializing);
  r.T_world_imu = f.odom.state.pose();
  r.lio_ms = f.stats.lio_ms;
  r.vio_ms = f.stats.vio_ms;
  r.map_ms = f.stats.map_ms;
  r.total_ms = f.stats.total_ms;
  r.sigma_min = f.stats.sigma_min;
  r.degenerate = f.stats.degenerate;
  r.visual_used = f.stats.visual_used;
  r.n_points = f.stats.n_points;
  r.n_planes_matched = f.stats.n_planes_matched;
  r.n_visual_points = f.stats.n_visual_points;
  return r;
}

}  // namespace

TEST(ExporterNode, TrajectoryAndCsvEqualLivoRunsAndAreFlushedPerFrame) {
  const auto frames = test::makeEstimatorFrames(20);
  const std::string dir = tempDir("exporter_files"), ref_dir = tempDir("exporter_ref");
  {
    RunOutputs ref(ref_dir);  // what livo-run writes for the same frames
    for (const auto& f : frames) ref.addFrame(recordOf(f));
  }
  LcmNode lcm("memq://", "livo-exporter", nullptr);
  MapExportConfig cfg;
  ExporterNode node(lcm, ChannelConfig{}, cfg, dir, nullptr);
  publishFrames(lcm, {frames.begin(), frames.begin() + 10});
  // Before any stop: every complete frame is already on disk (a killed exporter loses none of them).
  const auto ref_tum = lines(readFile(ref_dir + "/trajectory.tum"));
  const auto partial = lines(readFile(dir + "/trajectory.tum"));
  ASSERT_EQ(partial.size(), 10u);  // '#' header + frames 1..9 (frame 0 is initializing)
  EXPECT_TRUE(std::equal(partial.begin(), partial.end(), ref_tum.begin()));
  EXPECT_EQ(lines(readFile(dir + "/frames.csv")).size(), 11u);  // header + 10 rows
  publishFrames(lcm, {frames.begin() + 10, frames.end()});
  node.finish();

  EXPECT_EQ(readFile(dir + "/trajectory.tum"), readFile(ref_dir + "/trajectory.tum"));
  EXPECT_EQ(readFile(dir + "/frames.csv"), readFile(ref_dir + "/frames.csv"));
  const Trajectory traj = readTum(dir + "/trajectory.tum");
  ASSERT_EQ(traj.size(), 19u);  // the first frame was initializing
  EXPECT_NEAR(traj.back().t, toSeconds(frames.back().odom.utime), 1e-9);
  EXPECT_TRUE(traj.back().T_world_body.isApprox(frames.back().odom.state.pose(), 1e-8));

  const std::string stats = readFile(dir + "/stats.json");
  EXPECT_NE(stats.find("\"frames\": 20"), std::string::npos) << stats;
  EXPECT_NE(stats.find("\"visual_frames\": 5"), std::string::npos) << stats;
  EXPECT_NE(stats.find("\"degenerate_frames\": 1"), std::string::npos) << stats;
  // The newest map_stats_t (frame 19) is the map section.
  EXPECT_NE(stats.find("\"map\": {\"local_voxels\": 119, \"visual_points_local\": 69, "
                       "\"visual_points_longterm\": 133, \"bytes\": 1019000}"),
            std::string::npos)
      << stats;
  EXPECT_NE(stats.find("\"map_slides\": 3"), std::string::npos) << stats;
  EXPECT_NE(stats.find("\"timing_ms\""), std::string::npos);
}

TEST(ExporterNode, MapPcdIsColouredWhereTheCameraSawThePoints) {
  const auto frames = test::makeEstimatorFrames(6);
  const std::string dir = tempDir("exporter_pcd");
  LcmNode lcm("memq://", "livo-exporter", nullptr);
  MapExportConfig cfg;
  cfg.map_voxel_m = 0.05;
  ExporterNode node(lcm, ChannelConfig{}, cfg, dir, nullptr);
  publishFrames(lcm, frames);
  node.finish();

  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(dir + "/map.pcd", cloud), 0);
  EXPECT_EQ(cloud.size(), node.mapCloud().size());
  // Oracle: the distinct 5 cm voxels of all input points.
  std::set<std::tuple<long, long, long>> voxels;
  for (const auto& f : frames)
    for (const auto& p : f.scan.points)
      voxels.insert({std::lround(std::floor(p.x() / 0.05)), std::lround(std::floor(p.y() / 0.05)),
                     std::lround(std::floor(p.z() / 0.05))});
  EXPECT_EQ(cloud.size(), voxels.size());
  std::size_t red = 0, gray = 0;
  for (const auto& q : cloud) {
    EXPECT_NEAR(q.x, 5.0f, 1e-4);
    if (q.y > 0.0f) {  // seen by the camera: its colour
      EXPECT_EQ(int(q.r), 255);
      EXPECT_EQ(int(q.g), 0);
      EXPECT_EQ(int(q.b), 0);
      ++red;
    } else {  // not seen: gray from the intensity (100 = the largest: white)
      EXPECT_EQ(int(q.r), 255);
      EXPECT_EQ(int(q.g), 255);
      EXPECT_EQ(int(q.b), 255);
      ++gray;
    }
  }
  EXPECT_GT(red, 100u);
  EXPECT_GT(gray, 100u);
}

TEST(ExporterNode, MapBtIsOccupiedAtThePointsAndFreeAlongTheRays) {
  const auto frames = test::makeEstimatorFrames(6);
  const std::string dir = tempDir("exporter_bt");
  LcmNode lcm("memq://", "livo-exporter", nullptr);
  MapExportConfig cfg;
  cfg.octomap_resolution_m = 0.1;
  ExporterNode node(lcm, ChannelConfig{}, cfg, dir, nullptr);
  // Scans before their odometry: held until the origin is known.
  for (const auto& f : frames) {
    lcm.publish("LIVO_REGISTERED_SCAN", toMsg(f.scan));
    lcm.publish("LIVO_ESTIMATOR_STATS", toMsg(f.stats));
    lcm.publish("LIVO_ODOMETRY", toMsg(f.odom));
    lcm.drain();
  }
  node.finish();
  EXPECT_EQ(node.occupancy().scansInserted(), 6u);
  EXPECT_EQ(node.counters().count("scans_without_origin"), 0u);

  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(dir + "/map.bt"));
  EXPECT_DOUBLE_EQ(tree.getResolution(), 0.1);
  std::size_t occupied = 0, checked = 0;
  for (const auto& p : frames[3].scan.points) {
    if (p.z() < 0.15f || p.z() > 1.85f || std::abs(p.y()) > 0.85f) continue;  // inner wall only
    const octomap::OcTreeNode* n = tree.search(p.x(), p.y(), p.z());
    ++checked;
    occupied += n != nullptr && tree.isNodeOccupied(n);
  }
  EXPECT_GT(checked, 100u);
  EXPECT_EQ(occupied, checked);
  // Free space between the sensor (x <= 0.5, z = 1) and the wall at x = 5.
  for (double x : {1.0, 2.0, 3.0, 4.0}) {
    const octomap::OcTreeNode* n = tree.search(x, 0.0, 1.0);
    ASSERT_NE(n, nullptr) << "x=" << x;
    EXPECT_FALSE(tree.isNodeOccupied(n)) << "x=" << x;
  }
  EXPECT_EQ(tree.search(-3.0, 0.0, 1.0), nullptr);  // behind the sensor: unknown
  EXPECT_EQ(tree.search(7.0, 0.0, 1.0), nullptr);   // behind the wall: unknown
}

TEST(ExporterNode, LateLostAndReorderedMessagesKeepTheTrajectoryIncreasing) {
  const auto frames = test::makeEstimatorFrames(8);
  const std::string dir = tempDir("exporter_order");
  std::ostringstream log;
  LcmNode lcm("memq://", "livo-exporter", &log);
  ExporterNode node(lcm, ChannelConfig{}, MapExportConfig{}, dir, &log);
  for (int k = 0; k < 8; ++k) {
    const auto& f = frames[std::size_t(k)];
    if (k == 3) {  // stats first, then odometry
      node.onStats(f.stats);
      node.onOdometry(f.odom);
    } else if (k == 5) {  // stats lost
      node.onOdometry(f.odom);
    } else {
      node.onOdometry(f.odom);
      node.onStats(f.stats);
    }
  }
  node.onOdometry(frames[2].odom);  // late duplicate
  node.finish();
  const Trajectory traj = readTum(dir + "/trajectory.tum");  // throws unless strictly increasing
  EXPECT_EQ(traj.size(), 7u);
  const auto csv = lines(readFile(dir + "/frames.csv"));
  EXPECT_EQ(csv.size(), 9u);  // header + 8 frames (frame 5 with zero timings)
  EXPECT_DOUBLE_EQ(node.counters().at("frames_without_stats"), 1.0);
  EXPECT_DOUBLE_EQ(node.counters().at("odometry_late"), 1.0);
  EXPECT_NE(log.str().find("dropped odometry"), std::string::npos) << log.str();
}

TEST(ExporterNode, EmptyRunWritesValidFiles) {
  const std::string dir = tempDir("exporter_empty");
  LcmNode lcm("memq://", "livo-exporter", nullptr);
  ExporterNode node(lcm, ChannelConfig{}, MapExportConfig{}, dir, nullptr);
  node.finish();
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  EXPECT_EQ(pcl::io::loadPCDFile(dir + "/map.pcd", cloud), 0);
  EXPECT_TRUE(cloud.empty());
  octomap::OcTree tree(0.1);
  EXPECT_TRUE(tree.readBinary(dir + "/map.bt"));
  EXPECT_NE(readFile(dir + "/stats.json").find("\"frames\": 0"), std::string::npos);
}

// ---------------------------------------------------------------- MapCloud oracle

TEST(MapCloud, VoxelCentroidsAndColoursMatchBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  MapExportConfig cfg;
  cfg.map_voxel_m = 0.5;
  MapCloud cloud(cfg);
  struct Acc {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int n = 0, nc = 0;
    Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
  };
  std::map<std::tuple<long, long, long>, Acc> oracle;
  for (int batch = 0; batch < 5; ++batch) {
    std::vector<Eigen::Vector3f> pts;
    std::vector<float> intensity;
    std::vector<std::int32_t> rgb;
    for (int i = 0; i < 400; ++i) {
      const Eigen::Vector3f p(u(rng), u(rng), u(rng));
      const std::int32_t c = (i % 3 == 0) ? -1 : std::int32_t(rng() & 0xFFFFFF);
      pts.push_back(p);
      intensity.push_back(1.0f);
      rgb.push_back(c);
      Acc& a = oracle[{std::lround(std::floor(p.x() / 0.5)), std::lround(std::floor(p.y() / 0.5)),
                       std::lround(std::floor(p.z() / 0.5))}];
      a.sum += p.cast<double>();
      ++a.n;
      if (c >= 0) {
        ++a.nc;
        a.rgb += Eigen::Vector3d((c >> 16) & 0xFF, (c >> 8) & 0xFF, c & 0xFF);
      }
    }
    cloud.add(pts, intensity, rgb);
  }
  const std::string dir = tempDir("mapcloud");
  cloud.writePcd(dir + "/map.pcd");
  pcl::PointCloud<pcl::PointXYZRGB> out;
  ASSERT_EQ(pcl::io::loadPCDFile(dir + "/map.pcd", out), 0);
  ASSERT_EQ(out.size(), oracle.size());
  for (const auto& q : out) {
    const auto key = std::make_tuple(std::lround(std::floor(q.x / 0.5)), std::lround(std::floor(q.y / 0.5)),
                                     std::lround(std::floor(q.z / 0.5)));
    ASSERT_TRUE(oracle.count(key));
    const Acc& a = oracle.at(key);
    EXPECT_LT((Eigen::Vector3d(q.x, q.y, q.z) - a.sum / a.n).norm(), 1e-4);
    if (a.nc > 0) {
      EXPECT_NEAR(q.r, a.rgb.x() / a.nc, 0.51);
      EXPECT_NEAR(q.g, a.rgb.y() / a.nc, 0.51);
      EXPECT_NEAR(q.b, a.rgb.z() / a.nc, 0.51);
    }
  }
}

namespace {

/// MapExportConfig::load of `exporter: {KEY_VALUE}` throws a ConfigError naming `name`.
void expectExporterKeyRefused(const std::string& key_value, const std::string& name) {
  ConfigFile file = ConfigFile::parse("exporter: {" + key_value + "}\n", "rig.yaml");
  MapExportConfig loaded;
  try {
    loaded.load(file.root().section("exporter"));
    ADD_FAILURE() << key_value << " was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(MapCloud, CapOnPointsAndNonFiniteInputAreCounted) {
  MapExportConfig cfg;
  cfg.map_voxel_m = 1.0;
  cfg.max_map_points = 3;
  MapCloud cloud(cfg);
  std::vector<Eigen::Vector3f> pts{{0.5f, 0.5f, 0.5f}, {1.5f, 0.5f, 0.5f}, {2.5f, 0.5f, 0.5f},
                                   {3.5f, 0.5f, 0.5f}, {0.6f, 0.6f, 0.6f}, {NAN, 0.f, 0.f},
                                   {1e9f, 0.f, 0.f}};
  cloud.add(pts, std::vector<float>(pts.size(), 1.0f), {});
  EXPECT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.pointsAdded(), 4u);    // 3 voxels + one more point in the first
  EXPECT_EQ(cloud.pointsDropped(), 3u);  // over the cap, NaN, out of the key range
  EXPECT_THROW(cloud.add(pts, {1.0f}, {}), std::invalid_argument);
  MapExportConfig bad;
  bad.octomap_every_n = 0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  expectExporterKeyRefused("map_voxel_m: -1", "exporter.map_voxel_m");
}

TEST(OccupancyMap, MemoryCapStopsTheTreeGrowingAndCountsTheScansLeftOut) {
  // A rig driving along x past a wall at y = 6 m: every scan adds new free space and new hits.
  const auto scan = [](int i, Eigen::Vector3d& origin) {
    origin = Eigen::Vector3d(1.0 * i, 0.0, 1.0);
    std::vector<Eigen::Vector3f> pts;
    for (int a = -40; a <= 40; ++a)
      for (int h = 0; h <= 10; ++h) pts.emplace_back(float(origin.x() + 0.1 * a), 6.0f, float(0.2 * h));
    return pts;
  };
  constexpr int kScans = 40;
  MapExportConfig cfg;
  cfg.octomap_resolution_m = 0.1;
  cfg.octomap_queue_scans = 0;  // in this thread: the cap is checked in a known order
  cfg.octomap_max_mb = 0.0;     // no cap
  OccupancyMap full(cfg);
  Eigen::Vector3d origin;
  for (int i = 0; i < kScans; ++i) full.insertScan(origin, scan(i, origin));
  const double full_bytes = full.memoryBytes();
  // The cap counts malloc's chunks too: never less than OctoMap's own count.
  EXPECT_GE(full_bytes, double(full.tree().memoryUsage()));
  EXPECT_EQ(full.scansCapped(), 0u);
  EXPECT_TRUE(full.capNote().empty());

  cfg.octomap_max_mb = 0.5 * full_bytes / (1024.0 * 1024.0);
  OccupancyMap capped(cfg);
  for (int i = 0; i < kScans; ++i) capped.insertScan(origin, scan(i, origin));
  ASSERT_GT(capped.cappedAtScan(), 0u);
  EXPECT_LT(capped.cappedAtScan(), std::uint64_t(kScans));
  EXPECT_EQ(capped.scansInserted(), capped.cappedAtScan());
  EXPECT_EQ(capped.scansInserted() + capped.scansCapped(), std::uint64_t(kScans));
  // Checked whenever the tree grew by 5 %: it stops within that plus one scan's growth of the cap.
  const double per_scan = full_bytes / kScans;
  EXPECT_GT(capped.memoryBytes(), cfg.octomap_max_mb * 1024 * 1024);
  EXPECT_LT(capped.memoryBytes(), 1.05 * cfg.octomap_max_mb * 1024 * 1024 + 2 * per_scan);
  EXPECT_NE(capped.capNote().find("map.bt stopped growing at exporter.octomap_max_mb"), std::string::npos)
      << capped.capNote();
  expectExporterKeyRefused("octomap_max_mb: -1", "exporter.octomap_max_mb");
}

// ---------------------------------------------------------------- speed (opt-in)
// ./test_process_exporter --gtest_also_run_disabled_tests --gtest_filter='*Speed*'

TEST(ProcessSpeed, DISABLED_ExporterMsPerRegisteredScan) {
  // A sensor moving through a 20 x 8 x 3 m box; 5,000 world points per frame on its walls, 50 frames,
  // inserted in the caller's thread (octomap_queue_scans 0) to time the ray casting.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<OdometryOutput> odoms;
  std::vector<RegisteredScan> scans;
  for (int k = 0; k < 50; ++k) {
    OdometryOutput o;
    o.utime = o.state.utime = test::kStreamT0 + 100000 * k;
    o.state.p_world_imu = Eigen::Vector3d(1.0 + 0.3 * k, 4.0, 1.5);
    RegisteredScan s;
    s.utime = o.utime;
    for (int i = 0; i < 5000; ++i) {
      const float a = u(rng), b = u(rng);
      Eigen::Vector3f p;
      switch (i % 4) {
        case 0: p = {20.0f * a, 0.0f, 3.0f * b}; break;
        case 1: p = {20.0f * a, 8.0f, 3.0f * b}; break;
        case 2: p = {20.0f * a, 8.0f * b, 0.0f}; break;
        default: p = {20.0f, 8.0f * a, 3.0f * b}; break;
      }
      s.points.push_back(p);
      s.intensity.push_back(50.0f);
      s.rgb.push_back(i % 2 ? 0x808080 : -1);
    }
    odoms.push_back(o);
    scans.push_back(std::move(s));
  }
  for (double res : {0.3, 0.2, 0.1}) {
    const std::string dir = tempDir("exporter_speed");
    LcmNode lcm("memq://", "livo-exporter", nullptr);
    MapExportConfig cfg;
    cfg.octomap_resolution_m = res;
    cfg.octomap_queue_scans = 0;
    ExporterNode node(lcm, ChannelConfig{}, cfg, dir, nullptr);
    Stopwatch watch;
    for (std::size_t k = 0; k < odoms.size(); ++k) {
      node.onOdometry(odoms[k]);
      node.onRegisteredScan(scans[k]);
    }
    const double per_scan = watch.elapsedMs() / double(odoms.size());
    Stopwatch finish;
    node.finish();
    std::printf("exporter: octomap %.1f m: %.2f ms per registered scan of 5000 points (voxel map + rays); finish "
                "(stats.json, map.pcd %zu points, map.bt %zu leaves) %.1f ms\n",
                res, per_scan, node.mapCloud().size(), node.occupancy().leafCount(), finish.elapsedMs());
  }
}
