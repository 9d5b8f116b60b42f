// What reaches livo-viewer's drawing (libs/viewer, libs/process viewer_node): the inbox drops the
// oldest scans and replaced images it was not asked for, counted, and keeps every pose; the message
// adapter over memq:// converts each channel and counts rejects; a run directory loads or fails naming
// the file; the screenshot sidecar and the camera inset.
// livo-test-deps: livo_process
#include "livo/io/convert.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/io/loop_messages.hpp"
#include "livo/io/map_messages.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/viewer_node.hpp"
#include "livo/viewer/inbox.hpp"
#include "livo/viewer/inset.hpp"
#include "livo/viewer/run_directory.hpp"
#include "livo/viewer/scene.hpp"
#include "livo/viewer/screenshot.hpp"

#include "process_test_files.hpp"

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace livo;
using namespace livo::viewer;

namespace {

ScanInput scanAt(Utime t, std::size_t n = 3) {
  ScanInput s;
  s.utime = t;
  for (std::size_t i = 0; i < n; ++i) s.points.emplace_back(float(i), 0.f, 0.f);
  return s;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ViewerInbox, DropsTheOldestScansAndReplacedImagesKeepsEveryPose) {
  Inbox inbox(3);
  for (Utime t = 1; t <= 10; ++t) {
    inbox.pushScan(scanAt(t));
    inbox.pushPose(PoseInput{t, Pose::Identity(), false});
  }
  Image img;
  img.width = img.height = 1;
  img.data = {7};
  inbox.pushImage(img);
  inbox.pushImage(img);
  inbox.pushMapStats(MapStatsInput{1, 10, 0, 0, 0});
  inbox.pushMapStats(MapStatsInput{2, 20, 0, 0, 0});
  inbox.setRejected(4);
  InboxBatch b = inbox.take();
  ASSERT_EQ(b.scans.size(), 3u);
  EXPECT_EQ(b.scans.front().utime, 8);  // the newest three, oldest first
  EXPECT_EQ(b.scans.back().utime, 10);
  EXPECT_EQ(b.poses.size(), 10u);
  ASSERT_TRUE(b.image);
  ASSERT_TRUE(b.map_stats);
  EXPECT_EQ(b.map_stats->bytes, 20);
  EXPECT_EQ(b.drops.scans, 7u);
  EXPECT_EQ(b.drops.images, 1u);
  EXPECT_EQ(b.drops.rejected, 4u);
  EXPECT_EQ(b.drops.total(), 12u);
  const InboxBatch again = inbox.take();
  EXPECT_TRUE(again.empty());
  EXPECT_EQ(again.drops.scans, 7u) << "totals since the start";
  EXPECT_THROW(Inbox(0), std::invalid_argument);
}

TEST(ViewerNode, ConvertsEveryChannelOverMemqAndCountsRejects) {
  LcmNode lcm("memq://", "livo-viewer", nullptr);
  Inbox inbox(2);
  ChannelConfig ch;
  ViewerNode node(lcm, ch, inbox, /*camera=*/true);
  EXPECT_EQ(node.channelList(),
            "LIVO_REGISTERED_SCAN + LIVO_ODOMETRY + LIVO_ESTIMATOR_STATS + LIVO_MAP_STATS + LIVO_MAP_CORRECTION + "
            "LIVO_CAMERA");

  for (int i = 1; i <= 5; ++i) {  // five scans into a queue of two: three dropped
    RegisteredScan s;
    s.utime = i * 100000;
    s.points = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(4, 5, 6)};
    s.intensity = {0.5f, 0.25f};
    s.rgb = {0x112233, -1};
    lcm.publish(ch.registered_scan, toMsg(s));
  }
  OdometryOutput o;
  o.utime = 200000;
  o.state.utime = o.utime;
  o.state.p_world_imu = Vec3(1, 2, 3);
  o.status = odometry_status::kDegenerate;
  lcm.publish(ch.odometry, toMsg(o));
  OdometryOutput init = o;
  init.utime = 100000;
  init.status = odometry_status::kInitializing;  // no pose yet: not drawn
  lcm.publish(ch.odometry, toMsg(init));
  EstimatorStats st;
  st.utime = 200000;
  st.total_ms = 11.5f;
  st.sigma_min = 0.2f;
  lcm.publish(ch.estimator_stats, toMsg(st));
  MapStats ms;
  ms.utime = 200000;
  ms.bytes = 1234;
  ms.visual_points_local = 3;
  ms.visual_points_longterm = 4;
  lcm.publish(ch.map_stats, toMsg(ms));
  Image img;
  img.utime = 200000;
  img.width = 4;
  img.height = 2;
  img.row_stride = 4;
  img.data = {1, 2, 3, 4, 5, 6, 7, 8};
  lcm.publish(ch.camera, toMsg(img));
  const std::uint8_t junk[5] = {1, 2, 3, 4, 5};
  lcm.publishRaw(ch.odometry, junk, sizeof junk);  // undecodable: rejected
  lcm.drain();
  node.syncCounters();

  const InboxBatch b = inbox.take();
  ASSERT_EQ(b.scans.size(), 2u);
  EXPECT_EQ(b.scans.back().utime, 500000);
  EXPECT_EQ(b.scans.back().points[1], Eigen::Vector3f(4, 5, 6));
  EXPECT_EQ(b.scans.back().rgb[0], 0x112233);
  EXPECT_EQ(b.drops.scans, 3u);
  ASSERT_EQ(b.poses.size(), 1u);
  EXPECT_EQ(b.poses[0].utime, 200000);
  EXPECT_TRUE(b.poses[0].degenerate);
  EXPECT_LT((b.poses[0].T_world_imu.translation() - Vec3(1, 2, 3)).norm(), 1e-12);
  ASSERT_EQ(b.frame_stats.size(), 1u);
  EXPECT_FLOAT_EQ(b.frame_stats[0].total_ms, 11.5f);
  ASSERT_TRUE(b.map_stats);
  EXPECT_EQ(b.map_stats->bytes, 1234);
  EXPECT_EQ(b.map_stats->visual_points, 7);
  ASSERT_TRUE(b.image);
  EXPECT_EQ(b.image->width, 4);
  EXPECT_EQ(b.image->data[5], 6);
  EXPECT_EQ(b.drops.rejected, 1u);
}

namespace {

/// Keyframe i at (10 i, 0, 0); after `solved`, its map pose is lifted by 0.1 i in y.
MapCorrection correctionUpTo(int n, bool solved, int first) {
  MapCorrection c;
  c.keyframes_total = n;
  c.first = first;
  for (int i = first; i < n; ++i) {
    KeyframePose k;
    k.utime = Utime(i + 1) * 1'000'000;
    k.T_odom.translation() = Vec3(10.0 * i, 0, 0);
    k.T_map = k.T_odom;
    if (solved) k.T_map.translation().y() = 0.1 * i;
    c.keyframes.push_back(k);
  }
  if (solved) c.loops = {{0, n - 1}};
  return c;
}

}  // namespace

// livo-loop's corrections reach the scene through the adapter: the corrected keyframe path, the loop
// edges between map-frame keyframes, the overlay's counts; a flood of corrections is bounded in the
// inbox without losing the state (a full correction replaces what came before it).
TEST(ViewerNode, LoopCorrectionsBecomeTheCorrectedPathAndLoopEdges) {
  LcmNode lcm("memq://", "livo-viewer", nullptr);
  Inbox inbox(2);
  ChannelConfig ch;
  ViewerNode node(lcm, ch, inbox, /*camera=*/false);
  for (int n = 1; n <= 4; ++n) lcm.publish(ch.map_correction, toMsg(correctionUpTo(n, false, n - 1)));
  lcm.publish(ch.map_correction, toMsg(correctionUpTo(5, true, 0)));  // a solve: all keyframes, one loop
  livo::map_correction_t bad = toMsg(correctionUpTo(5, true, 0));
  bad.loop_to[0] = 7;  // beyond the graph: rejected
  lcm.publish(ch.map_correction, bad);
  lcm.drain();
  node.syncCounters();
  Scene scene{SceneConfig{}};
  const std::uint64_t v0 = scene.mapFrameVersion();
  scene.apply(inbox.take());
  EXPECT_NE(scene.mapFrameVersion(), v0);
  const std::vector<Vec3> path = scene.mapFramePath();
  ASSERT_EQ(path.size(), 5u);
  EXPECT_LT((path[4] - Vec3(40, 0.4, 0)).norm(), 1e-9);
  const auto edges = scene.loopEdges();
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_LT((edges[0].first - Vec3(0, 0, 0)).norm(), 1e-9);
  EXPECT_LT((edges[0].second - Vec3(40, 0.4, 0)).norm(), 1e-9);
  const std::string text = overlayText(scene.overlay("live", ViewMode::kTop, ColourMode::kHeight));
  EXPECT_NE(text.find("loop closure: 5 keyframes, 1 loops"), std::string::npos) << text;
  EXPECT_NE(text.find("1 rejected"), std::string::npos) << text;

  // More corrections than the inbox holds: the ones before the newest full correction go (counted).
  Inbox small;
  for (int n = 1; n <= int(Inbox::kMaxCorrections) + 10; ++n) {
    small.pushCorrection(correctionUpTo(n, false, n - 1));
    if (n == 100) small.pushCorrection(correctionUpTo(n, true, 0));
  }
  InboxBatch b = small.take();
  // At the 257th, the 100 before the full one (pushed after the 100th) went; 166 followed it.
  EXPECT_EQ(b.corrections.size(), 167u);
  EXPECT_EQ(b.drops.corrections, 100u);
  Scene flooded{SceneConfig{}};
  flooded.apply(std::move(b));
  EXPECT_EQ(flooded.mapFramePath().size(), Inbox::kMaxCorrections + 10) << "every keyframe kept";
  EXPECT_EQ(flooded.loopEdges().size(), 1u);
}

TEST(ViewerRunDirectory, LoadsTrajectoryAndColouredMap) {
  const std::string dir = test::tempDir("viewer_run_ok");
  std::ofstream(dir + "/trajectory.tum") << "# t x y z qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.1 1 0 0 0 0 0 1\n";
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  pcl::PointXYZRGB p;
  p.x = 1;
  p.y = 2;
  p.z = 3;
  p.r = 10;
  p.g = 20;
  p.b = 30;
  cloud.push_back(p);
  ASSERT_EQ(pcl::io::savePCDFileBinary(dir + "/map.pcd", cloud), 0);
  const RunDirectory run = loadRunDirectory(dir);
  ASSERT_EQ(run.poses.size(), 2u);
  EXPECT_EQ(run.poses[1].utime, 1100000);
  EXPECT_DOUBLE_EQ(run.poses[1].T_world_imu.translation().x(), 1.0);
  ASSERT_TRUE(run.has_map);
  ASSERT_EQ(run.map.points.size(), 1u);
  EXPECT_EQ(run.map.points[0], Eigen::Vector3f(1, 2, 3));
  EXPECT_EQ(run.map.rgb[0], 0x0A141E);
  EXPECT_NE(run.map_note.find("1 points"), std::string::npos) << run.map_note;

  std::filesystem::remove(dir + "/map.pcd");  // livo-run --no-maps: the trajectory alone
  const RunDirectory bare = loadRunDirectory(dir);
  EXPECT_FALSE(bare.has_map);
  EXPECT_NE(bare.map_note.find("trajectory only"), std::string::npos);
}

TEST(ViewerRunDirectory, BadInputNamesTheFile) {
  const std::string dir = test::tempDir("viewer_run_bad");
  EXPECT_EQ(errorOf([&] { loadRunDirectory(dir + "/nope"); }), dir + "/nope: no such directory");
  EXPECT_EQ(errorOf([&] { loadRunDirectory(dir); }),
            dir + "/trajectory.tum: missing (not a livo-run / livo-exporter output directory?)");
  std::ofstream(dir + "/trajectory.tum") << "1.0 0 0 0 0 0 0 1\n1.1 zero 0 0 0 0 0 1\n";
  EXPECT_NE(errorOf([&] { loadRunDirectory(dir); }).find("trajectory.tum:2"), std::string::npos);
  std::ofstream(dir + "/trajectory.tum") << "1.0 0 0 0 0 0 0 1\n";
  std::ofstream(dir + "/map.pcd") << "this is not a point cloud\n";
  EXPECT_EQ(errorOf([&] { loadRunDirectory(dir); }),
            dir + "/map.pcd: not a PCD file (line 1: unknown header line 'this is not a point cloud')");
  // Headers PCL 1.13's reader crashes on are refused before it reads them.
  std::ofstream(dir + "/map.pcd") << "VERSION 0.7\nFIELDS x y z\nWIDTH 1\nDATA ascii\n1 2 3\n";
  EXPECT_EQ(errorOf([&] { loadRunDirectory(dir); }), dir + "/map.pcd: not a PCD file (no SIZE line)");
  std::ofstream(dir + "/map.pcd") << "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1000\nHEIGHT 1\nDATA binary\n"
                                  << std::string(100, '\0');
  EXPECT_EQ(errorOf([&] { loadRunDirectory(dir); }),
            dir + "/map.pcd: truncated PCD (100 bytes of data for 1000 points of 12 bytes)");
  std::ofstream(dir + "/map.pcd") << "VERSION 0.7\nFIELDS a b\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\n"
                                     "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2\n";
  EXPECT_EQ(errorOf([&] { loadRunDirectory(dir); }), dir + "/map.pcd: PCD without x, y, z fields (has: a b)");
}

TEST(ViewerScreenshot, SidecarHoldsTheCameraMatrixAndWhatIsDrawn) {
  ScreenshotInfo info;
  info.width = 640;
  info.height = 480;
  info.world_to_ndc(0, 3) = 0.25;
  info.view = "top";
  info.colour = "height";
  info.poses = 12;
  info.map_points = 3456;
  info.first_utime = 1000000;
  info.last_utime = 2500000;
  info.message_time_s = 1.5;
  EXPECT_EQ(screenshotJson(info),
            "{\"width\": 640, \"height\": 480, \"world_to_ndc\": [1, 0, 0, 0.25, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1], "
            "\"view\": \"top\", \"colour\": \"height\", \"poses\": 12, \"map_points\": 3456, \"first_utime\": 1000000, "
            "\"last_utime\": 2500000, \"message_time_s\": 1.500000}\n");
  EXPECT_EQ(sidecarPath("out/shot.png"), "out/shot.json");
  EXPECT_EQ(sidecarPath("shot"), "shot.json");
}

TEST(ViewerInset, ShrinksByAnIntegerFactorWithABoxAverage) {
  Image g;
  g.width = 6;
  g.height = 4;
  g.row_stride = 8;  // padded rows
  g.data.assign(8 * 4, 0);
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 6; ++u) g.data[v * 8 + u] = static_cast<std::uint8_t>(10 * u + v);
  const Image s = shrinkGray8(g, 3);  // factor 2
  ASSERT_EQ(s.width, 3);
  ASSERT_EQ(s.height, 2);
  // Block (u 2..3, v 0..1): (20 + 30 + 21 + 31) / 4 = 25.5 -> 26 (rounded).
  EXPECT_EQ(s.data[1], 26);
  EXPECT_EQ(shrinkGray8(g, 100).width, 6) << "fits: factor 1";
  Image rgb = g;
  rgb.format = PixelFormat::Rgb8;
  EXPECT_THROW(shrinkGray8(rgb, 3), std::invalid_argument);
  Image short_buf = g;
  short_buf.data.resize(10);
  EXPECT_THROW(shrinkGray8(short_buf, 3), std::invalid_argument);
}
