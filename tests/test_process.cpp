// libs/process: typed LCM subscriptions (validation, reject counters, literal channel names), the
// processes' command line, and the cores of livo-preprocess and livo-exporter driven over memq://
// (one process, no network): frames at the image times, bad messages counted, output files equal to
// livo-run's (RunOutputs), map.pcd coloured where the camera saw the points (read back with PCL),
// map.bt occupied at the points and free along the rays (read back with OctoMap).
#include "livo/common/timing.hpp"
#include "livo/eval/tum.hpp"
#include "livo/io/run_outputs.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/exporter_node.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/map_export.hpp"
#include "livo/process/preprocess_node.hpp"

#include "process_test_streams.hpp"

#include <octomap/OcTree.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <tuple>
#include <sstream>
#include <unistd.h>

using namespace livo;
namespace fs = std::filesystem;

namespace {

fs::path tempRoot() { return fs::temp_directory_path() / ("livo_test_process_" + std::to_string(::getpid())); }

/// Removes the temporary files of this run when every test passed (kept for inspection otherwise).
struct TempCleanup : testing::Environment {
  void TearDown() override {
    if (testing::UnitTest::GetInstance()->Passed()) fs::remove_all(tempRoot());
  }
};
[[maybe_unused]] testing::Environment* const kTempCleanup = testing::AddGlobalTestEnvironment(new TempCleanup);

std::string tempDir(const std::string& name) {
  const fs::path p = tempRoot() / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream is(text);
  for (std::string l; std::getline(is, l);) out.push_back(l);
  return out;
}

PreprocessConfig cameraConfig() {
  PreprocessConfig cfg;
  cfg.camera_enabled = true;
  cfg.imu_rate_hz = 200.0;
  cfg.blind_m = 0.5;
  return cfg;
}

/// Collects every frame published on LIVO_FRAME of `lcm`.
struct FrameSink {
  std::vector<Frame> frames;
  explicit FrameSink(LcmNode& lcm) {
    lcm.subscribeStruct<livo::frame_t, Frame>("LIVO_FRAME", [this](Frame& f) { frames.push_back(f); });
  }
};

}  // namespace

// ---------------------------------------------------------------- LcmNode, CLI

TEST(LcmNode, ValidMessagesReachTheHandlerBadOnesAreCounted) {
  std::ostringstream log;
  LcmNode lcm("memq://", "test", &log);
  std::vector<ImuSample> got;
  lcm.subscribeStruct<livo::imu_t, ImuSample>("LIVO_IMU", [&](ImuSample& s) { got.push_back(s); });

  ImuSample s;
  s.utime = 123;
  s.gyro = Eigen::Vector3d(0.1, 0.2, 0.3);
  lcm.publish("LIVO_IMU", toMsg(s));
  const std::vector<std::uint8_t> garbage{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  lcm.publishRaw("LIVO_IMU", garbage.data(), garbage.size());
  std::vector<std::uint8_t> truncated = encode(toMsg(s));
  truncated.resize(truncated.size() - 3);
  lcm.publishRaw("LIVO_IMU", truncated.data(), truncated.size());
  livo::imu_t nan_msg = toMsg(s);
  nan_msg.angular_velocity[1] = std::nan("");
  lcm.publish("LIVO_IMU", nan_msg);
  lcm.drain();

  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].utime, 123);
  EXPECT_DOUBLE_EQ(got[0].gyro.y(), 0.2);
  const ChannelCounters& c = lcm.counters().at("LIVO_IMU");
  EXPECT_EQ(c.received, 4u);
  EXPECT_EQ(c.rejected, 3u);
  EXPECT_NE(c.last_error.find("imu_t"), std::string::npos) << c.last_error;
  EXPECT_NE(log.str().find("LIVO_IMU: rejected message (3 so far)"), std::string::npos) << log.str();
}

TEST(LcmNode, ChannelNamesAreLiteralNotRegularExpressions) {
  LcmNode lcm("memq://", "test", nullptr);
  int hits = 0;
  lcm.subscribeRaw("A.B*", [&](const void*, std::size_t) {
    ++hits;
    return Validation::ok();
  });
  const char byte = 0;
  lcm.publishRaw("AxBBB", &byte, 1);
  lcm.publishRaw("A.B*", &byte, 1);
  lcm.drain();
  EXPECT_EQ(hits, 1);
  EXPECT_TRUE(lcm.dispatch("A.B*", &byte, 1));
  EXPECT_FALSE(lcm.dispatch("other", &byte, 1));
  EXPECT_EQ(hits, 2);
}

TEST(LcmNode, HandlerExceptionsAreRejectsNotCrashes) {
  LcmNode lcm("memq://", "test", nullptr);
  lcm.subscribeRaw("X", [](const void*, std::size_t) -> Validation { throw std::runtime_error("disk full"); });
  const char byte = 0;
  lcm.publishRaw("X", &byte, 1);
  EXPECT_NO_THROW(lcm.drain());
  EXPECT_EQ(lcm.totalRejected(), 1u);
  EXPECT_NE(lcm.counters().at("X").last_error.find("disk full"), std::string::npos);
}

TEST(LcmNode, WarningsAreRateLimited) {
  std::vector<std::uint64_t> warned;
  for (std::uint64_t n = 0; n <= 20000; ++n)
    if (shouldWarn(n)) warned.push_back(n);
  EXPECT_EQ(warned, (std::vector<std::uint64_t>{1, 2, 3, 4, 5, 10, 100, 1000, 10000}));
}

TEST(LcmNode, UnusableUrlIsAnErrorNamingIt) {
  try {
    LcmNode lcm("nosuchprovider://x", "test", nullptr);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchprovider://x"), std::string::npos) << e.what();
  }
}

TEST(CommandLine, ParsesCommonOptionsAndNamesTheBadFlag) {
  auto parse = [](std::vector<const char*> argv, ProcessArgs& a, std::string* out = nullptr) {
    CommandLine cl("livo-x", "--config CFG", "test");
    addProcessOptions(cl, a);
    if (out) cl.option("--out", out, "DIR", "output");
    argv.insert(argv.begin(), "livo-x");
    return cl.parse(int(argv.size()), argv.data());
  };
  ProcessArgs a;
  std::string out;
  EXPECT_TRUE(parse({"--config", "c.yaml", "--lcm-url=memq://", "--idle-exit", "2.5", "--out", "d"}, a, &out));
  EXPECT_EQ(a.config, "c.yaml");
  EXPECT_EQ(a.lcm_url, "memq://");
  EXPECT_DOUBLE_EQ(a.idle_exit_s, 2.5);
  EXPECT_EQ(out, "d");

  auto error = [&](std::vector<const char*> argv) -> std::string {
    ProcessArgs b;
    try {
      parse(argv, b);
    } catch (const CliError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error({"--lcm-url", "x"}), "--config is required");
  EXPECT_EQ(error({"--config", "c", "--bogus"}), "unknown option --bogus");
  EXPECT_EQ(error({"--config"}), "--config needs a value (CFG.yaml)");
  EXPECT_EQ(error({"--config", "c", "--idle-exit", "soon"}), "--idle-exit: expected a number >= 0, got 'soon'");
  EXPECT_EQ(error({"--config", "c", "--idle-exit", "-1"}), "--idle-exit: expected a number >= 0, got '-1'");
  EXPECT_EQ(error({"--config", "c", "stray"}), "unexpected argument 'stray'");

  testing::internal::CaptureStdout();
  ProcessArgs h;
  EXPECT_FALSE(parse({"--help"}, h));
  const std::string help = testing::internal::GetCapturedStdout();
  EXPECT_NE(help.find("--lcm-url URL"), std::string::npos) << help;
  EXPECT_NE(help.find(kDefaultLcmUrl), std::string::npos) << help;
}

TEST(CommandLine, UnknownKeysInTheProcesssOwnSectionsAreErrors) {
  ConfigFile file = ConfigFile::parse(
      "lidar: {blind_m: 0.5, T_imu_lidar: [0, 0, 0, 0, 0, 0, 1]}\n"
      "preprocess: {wait_timeout_s: 0.4, wait_timout_s: 0.3}\n"
      "channels: {frame: MY_FRAME}\n",
      "rig.yaml");
  PreprocessConfig cfg;
  cfg.load(file.root());
  ChannelConfig ch;
  ch.load(file.root().section("channels"));
  EXPECT_EQ(ch.frame, "MY_FRAME");
  try {
    checkSectionsUsed(file, {"channels", "preprocess"});
    FAIL() << "expected an error for the typo";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rig.yaml: preprocess.wait_timout_s"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(checkSectionsUsed(file, {"channels"}));  // lidar.T_imu_lidar belongs to the estimator
}

// ---------------------------------------------------------------- PreprocessNode

TEST(PreprocessNode, PublishesOneFrameAtEachImageTimeOverMemq) {
  const test::SensorStream stream = test::makeSensorStream(2.0);
  std::ostringstream log;
  LcmNode lcm("memq://", "livo-preprocess", &log);
  FrameSink sink(lcm);
  PreprocessNode node(lcm, cameraConfig(), ChannelConfig{}, &log, 0.5);
  for (const auto& ev : stream.events) {
    lcm.publishRaw(ev.channel, ev.bytes.data(), ev.bytes.size());
    lcm.drain();
  }
  node.finish();
  lcm.drain();

  // One frame per image, then (at the end of input) one without image for the LiDAR points after the
  // last image (the recombiner's image_wait_timeout_s).
  ASSERT_EQ(sink.frames.size(), stream.image_times.size() + 1);
  EXPECT_FALSE(sink.frames.back().has_image);
  EXPECT_NEAR(double(sink.frames.back().utime), double(test::kStreamT0 + 1999500), 1.0);
  EXPECT_EQ(node.counters().frames_published, sink.frames.size());
  EXPECT_EQ(node.counters().frames_with_image, stream.image_times.size());
  EXPECT_EQ(lcm.totalRejected(), 0u) << lcm.countersSummary();
  Utime prev_end = 0;
  for (std::size_t i = 0; i < stream.image_times.size(); ++i) {
    const Frame& f = sink.frames[i];
    SCOPED_TRACE("frame " + std::to_string(i));
    EXPECT_EQ(f.utime, stream.image_times[i]);
    ASSERT_TRUE(f.has_image);
    EXPECT_EQ(f.image.utime, f.utime);
    EXPECT_EQ(f.image.format, PixelFormat::Gray8);
    ASSERT_EQ(f.image.width, 40);
    ASSERT_EQ(f.image.height, 30);
    // Gray of (4u, 100, 100): brightness rises with u, the same in every row.
    EXPECT_LT(f.image.data[0], f.image.data[39]);
    EXPECT_EQ(f.image.data[5], f.image.data[29 * 40 + 5]);
    if (i > 0) {
      EXPECT_EQ(f.sweep_start_utime, prev_end);
    }
    prev_end = f.utime;
    // Sweep: points in (sweep start, frame time] (the first sweep includes its first point).
    ASSERT_FALSE(f.sweep.points.empty());
    for (const auto& p : f.sweep.points) {
      const Utime t = f.sweep.utime + Utime(std::llround(1e6 * double(p.time_offset_s)));
      EXPECT_LE(t, f.utime + 1);
      if (i > 0) {
        EXPECT_GE(t, f.sweep_start_utime);
      }
    }
    // IMU brackets the sweep.
    ASSERT_GE(f.imu.size(), 2u);
    EXPECT_LE(f.imu.front().utime, f.sweep_start_utime);
    EXPECT_GE(f.imu.back().utime, f.utime);
  }
  // Periodic counters on message time: every 0.5 s of frame time over 1.9 s of frames.
  std::size_t reports = 0;
  for (const auto& l : lines(log.str())) reports += l.rfind("livo-preprocess: t ", 0) == 0;
  EXPECT_EQ(reports, 3u) << log.str();
  EXPECT_NE(node.summary().find("frames published 21 (20 with image"), std::string::npos) << node.summary();
}

TEST(PreprocessNode, BadMessagesAreCountedAndFramesStillFlow) {
  const test::SensorStream stream = test::makeSensorStream(2.0);
  std::ostringstream log;
  LcmNode lcm("memq://", "livo-preprocess", &log);
  FrameSink sink(lcm);
  PreprocessNode node(lcm, cameraConfig(), ChannelConfig{}, &log);
  const std::vector<std::uint8_t> garbage(64, 0xAB);
  Image jpeg;  // says JPEG, holds garbage: decodes as a message, fails in toGray8
  jpeg.utime = test::kStreamT0 + 1;
  jpeg.format = PixelFormat::Jpeg;
  jpeg.width = 40;
  jpeg.height = 30;
  jpeg.data.assign(100, 0x11);
  Image short_raw;  // raw RGB8 with too few bytes: fails validation
  short_raw.utime = test::kStreamT0 + 2;
  short_raw.format = PixelFormat::Rgb8;
  short_raw.width = 40;
  short_raw.height = 30;
  short_raw.row_stride = 120;
  short_raw.data.assign(50, 0);
  const livo::image_t short_msg = toMsg(short_raw);
  int injected = 0;
  for (const auto& ev : stream.events) {
    lcm.publishRaw(ev.channel, ev.bytes.data(), ev.bytes.size());
    if (ev.channel == "LIVO_LIDAR" && injected < 3) {
      ++injected;
      lcm.publishRaw("LIVO_LIDAR", garbage.data(), garbage.size());
      lcm.publishRaw("LIVO_IMU", garbage.data(), garbage.size());
      lcm.publish("LIVO_CAMERA", toMsg(jpeg));
      lcm.publish("LIVO_CAMERA", short_msg);
    }
    lcm.drain();
  }
  node.finish();
  lcm.drain();
  EXPECT_EQ(node.counters().frames_with_image, stream.image_times.size());
  EXPECT_EQ(sink.frames.size(), stream.image_times.size() + 1);
  EXPECT_EQ(lcm.counters().at("LIVO_LIDAR").rejected, 3u);
  EXPECT_EQ(lcm.counters().at("LIVO_IMU").rejected, 3u);
  EXPECT_EQ(lcm.counters().at("LIVO_CAMERA").rejected, 6u);
  EXPECT_EQ(node.counters().images_unconvertible, 3u);
  EXPECT_NE(log.str().find("LIVO_CAMERA: rejected message"), std::string::npos) << log.str();
}

TEST(PreprocessNode, LidarOnlyConfigFramesPerScanAndIgnoresImages) {
  const test::SensorStream stream = test::makeSensorStream(1.0);
  LcmNode lcm("memq://", "livo-preprocess", nullptr);
  FrameSink sink(lcm);
  PreprocessConfig cfg = cameraConfig();
  cfg.camera_enabled = false;
  ChannelConfig channels;
  channels.frame = "LIVO_FRAME";
  PreprocessNode node(lcm, cfg, channels, nullptr);
  const std::vector<std::uint8_t> garbage(16, 0);
  for (const auto& ev : stream.events) lcm.dispatch(ev.channel, ev.bytes.data(), ev.bytes.size());
  lcm.dispatch("LIVO_CAMERA", garbage.data(), garbage.size());  // not even decoded
  node.finish();
  lcm.drain();
  EXPECT_EQ(lcm.totalRejected(), 0u);
  EXPECT_EQ(node.recombiner().stats().images_ignored, stream.image_times.size() + 1);
  ASSERT_EQ(sink.frames.size(), 10u);  // one per scan
  for (std::size_t i = 0; i < sink.frames.size(); ++i) {
    EXPECT_FALSE(sink.frames[i].has_image);
    EXPECT_NEAR(double(sink.frames[i].utime), double(test::kStreamT0 + 100000 * Utime(i) + 99500), 1.0);  // scan i's last point
  }
}

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
  ConfigFile file = ConfigFile::parse("exporter: {map_voxel_m: -1}\n", "rig.yaml");
  MapExportConfig loaded;
  try {
    loaded.load(file.root().section("exporter"));
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("exporter.map_voxel_m"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------- speed (opt-in)
// ./test_process --gtest_also_run_disabled_tests --gtest_filter='*Speed*'

TEST(ProcessSpeed, DISABLED_PreprocessFramesPerSecond) {
  // Avia-like input: 24,000 points per 0.1 s scan, 640 x 512 RGB8 images at 10 Hz, IMU at 200 Hz.
  const test::SensorStream stream = test::makeSensorStream(5.0, 24000, 640, 512);
  std::size_t bytes = 0;
  for (const auto& ev : stream.events) bytes += ev.bytes.size();
  LcmNode lcm("memq://", "livo-preprocess", nullptr);
  std::size_t frames = 0;
  lcm.subscribeRaw("LIVO_FRAME", [&](const void*, std::size_t) {
    ++frames;
    return Validation::ok();
  });
  PreprocessNode node(lcm, cameraConfig(), ChannelConfig{}, nullptr);
  Stopwatch watch;
  for (const auto& ev : stream.events) {
    lcm.dispatch(ev.channel, ev.bytes.data(), ev.bytes.size());  // decode, convert, recombine, encode
    lcm.drain();                                                 // the published frames
  }
  node.finish();
  lcm.drain();
  const double s = watch.elapsedMs() / 1000.0;
  std::printf("preprocess: %zu frames in %.3f s = %.1f frames/s (%.1f MB/s of input, %.1f x real time)\n", frames, s,
              double(frames) / s, double(bytes) / 1e6 / s, 5.0 / s);
  EXPECT_EQ(frames, stream.image_times.size() + 1);
}

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
