// The core of livo-loop (libs/process LoopNode) and its consumer livo-exporter (ExporterNode) over
// memq://, fed the simulator's revisit scenario (one lap and the start of the second) with an odometry
// that drifts, as the estimator would send it (odometry, registered scan as floats, stats): the
// exporter's trajectory_map.tum against the LoopCloser and MapFrameTrajectory run directly on the same
// inputs (livo-run --loop's composition) and against the truth; frames without a scan, late frames.
// livo-test-deps: livo_sim
// livo-test-whole
#include "livo/eval/tum.hpp"
#include "livo/io/loop_messages.hpp"
#include "livo/loop/loop_closer.hpp"
#include "livo/loop/prior_seeder.hpp"
#include "livo/loop/relocaliser.hpp"
#include "livo/loop/site_map.hpp"
#include "livo/process/exporter_node.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/loop_node.hpp"
#include "livo/process/mapserver_node.hpp"
#include "livo/io/map_messages.hpp"

#include "loop_test_util.hpp"
#include "process_test_files.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace livo;

namespace {

/// One frame as the estimator sends it.
struct SentFrame {
  OdometryOutput odom;            ///< after a message round trip (what the receivers decode)
  RegisteredScan scan;            ///< empty points: no scan sent for this frame
  Pose truth = Pose::Identity();
};

/// The revisit scenario's first `duration_s`: every scan-to-scan step of the truth 0.5 % too long and
/// turned 0.004 deg too far (test_loop_closer's drift), the scans at the drifted poses. Every 10th frame
/// sends no scan.
std::vector<SentFrame> driftedFrames(double duration_s) {
  sim::SimScenario sc = test::revisitScenario();
  sc.duration_s = duration_s;
  const sim::Simulator s(sc);
  const std::int64_t scans = static_cast<std::int64_t>(duration_s * sc.lidar.rate_hz) - 1;
  std::vector<SentFrame> out;
  Pose odom = s.T_world_imu(s.lidarUtime(0)), prev_truth = odom;
  for (std::int64_t j = 0; j < scans; ++j) {
    const Pose truth = s.T_world_imu(s.lidarUtime(j));
    if (j > 0) odom = odom * test::driftedStep(prev_truth, truth);
    prev_truth = truth;
    SentFrame f;
    f.truth = truth;
    OdometryOutput o;
    o.utime = s.lidarUtime(j);
    o.state.utime = o.utime;
    o.state.R_world_imu = odom.linear();
    o.state.p_world_imu = odom.translation();
    o.pose_cov = Mat6::Identity() * 1e-4;
    o.status = odometry_status::kLidarUpdate;
    EXPECT_TRUE(fromMsg(toMsg(o), f.odom));
    f.scan.utime = o.utime;
    if (j % 10 != 5) {
      const Pose drift = odom * truth.inverse();
      for (const Vec3& p : test::worldScan(s, j)) f.scan.points.push_back((drift * p).cast<float>());
      f.scan.intensity.assign(f.scan.points.size(), 1.f);
    }
    out.push_back(std::move(f));
  }
  return out;
}

const std::vector<SentFrame>& frames() {
  // 56 s: 4 s of start, one 41 s lap of the 340 m block, 11 s (90 m) of the second.
  static const std::vector<SentFrame> f = driftedFrames(56.0);
  return f;
}

LoopConfig loopConfig() {
  const sim::SimScenario sc = test::revisitScenario();
  const ConfigFile f = ConfigFile::parse("loop: {}\n", "rig.yaml");
  LoopConfig cfg;
  cfg.load(f.root().section("loop"), sc.lidar.max_range_m, sc.lidar.range_noise_m, sc.lidar.beam_noise_deg);
  return cfg;
}

/// The frames as the estimator publishes them (odometry, scan when it has points, stats), each drained.
void publishFrames(LcmNode& lcm, const ChannelConfig& ch, const std::vector<SentFrame>& frames) {
  for (const SentFrame& f : frames) {
    lcm.publish(ch.odometry, toMsg(f.odom));
    if (!f.scan.points.empty()) lcm.publish(ch.registered_scan, toMsg(f.scan));
    EstimatorStats st;
    st.utime = f.odom.utime;
    lcm.publish(ch.estimator_stats, toMsg(st));
    lcm.drain();
  }
}

/// Points of a frame's scan in double precision (what the LoopCloser takes).
std::vector<Vec3> scanPoints(const SentFrame& f) {
  std::vector<Vec3> pts;
  for (const Eigen::Vector3f& p : f.scan.points) pts.push_back(p.cast<double>());
  return pts;
}

double rmsError(const Trajectory& est, const std::vector<SentFrame>& fr) {
  double s = 0;
  std::size_t n = 0;
  std::size_t k = 0;
  for (const StampedPose& p : est) {
    while (k < fr.size() && toSeconds(fr[k].odom.utime) < p.t - 1e-7) ++k;
    if (k == fr.size()) break;
    s += (p.T_world_body.translation() - fr[k].truth.translation()).squaredNorm();
    ++n;
  }
  return n ? std::sqrt(s / double(n)) : 1e9;
}

}  // namespace

TEST(LoopNode, ExporterWritesTheMapFrameOfTheLoopCloserRunDirectly) {
  const std::vector<SentFrame>& fr = frames();

  // The direct composition (livo-run --loop): LoopCloser on the decoded poses and the float points.
  LoopCloser direct(loopConfig());
  for (const SentFrame& f : fr)
    direct.add(f.odom.utime, f.odom.state.pose(), [&] { return scanPoints(f); });
  direct.finish();
  MapFrameTrajectory expected;
  ASSERT_EQ(expected.apply(direct.correctionMessage(true, true)), "");

  // The processes' cores on one memq bus: estimator messages in, corrections from LoopNode to the exporter.
  const std::string dir = test::tempDir("loop_node");
  LcmNode lcm("memq://", "test", nullptr);
  const ChannelConfig ch;
  ExporterNode exporter(lcm, ch, MapExportConfig{}, dir, nullptr);
  LoopNode loop(lcm, ch, loopConfig(), nullptr);
  int corrections = 0;
  lcm.subscribe<livo::map_correction_t>(ch.map_correction, [&](const livo::map_correction_t&) {
    ++corrections;
    return Validation::ok();
  });
  publishFrames(lcm, ch, fr);
  lcm.publish(ch.odometry, toMsg(fr[fr.size() / 2].odom));  // a late frame: dropped
  lcm.drain();
  loop.finish();
  lcm.drain();
  exporter.finish();

  ASSERT_NE(loop.closer(), nullptr);
  const LoopCloser& c = *loop.closer();
  std::printf("revisit 56 s, drifted odometry: %zu keyframes, %d loops, %d solves, %d corrections\n",
              c.graph().size(), c.loopsAccepted(), c.totals().solves, corrections);
  EXPECT_EQ(c.graph().size(), direct.graph().size());
  EXPECT_EQ(c.loopsAccepted(), direct.loopsAccepted());
  EXPECT_GE(c.loopsAccepted(), 2);
  EXPECT_EQ(corrections, int(c.graph().size()) + 1) << "one per keyframe and the final one";
  EXPECT_EQ(loop.counters().at("odometry_late"), 1.0);
  EXPECT_EQ(loop.counters().at("frames"), double(fr.size()));
  EXPECT_EQ(loop.counters().at("frames_without_scan"), double(fr.size() / 10 + (fr.size() % 10 > 5)));
  EXPECT_EQ(exporter.counters().at("map_frame_final"), 1.0);

  const Trajectory odom = readTum(dir + "/trajectory.tum");
  const Trajectory map = readTum(dir + "/trajectory_map.tum");
  ASSERT_EQ(map.size(), odom.size());
  ASSERT_EQ(odom.size(), fr.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < fr.size(); ++i) {
    const auto T = expected.toMap(fr[i].odom.utime, fr[i].odom.state.pose());
    ASSERT_TRUE(T);
    worst = std::max(worst, (T->translation() - map[i].T_world_body.translation()).norm());
  }
  const double e_odom = rmsError(odom, fr), e_map = rmsError(map, fr);
  std::printf("position rms against the truth: odometry %.3f m, map frame %.3f m; exporter vs direct %.2g m\n", e_odom,
              e_map, worst);
  EXPECT_LT(worst, 1e-5) << "the TUM file's precision";
  // 2026-12-06: odometry 1.097 m rms, map frame 0.289 m (161 keyframes, 5 loops, 2 solves): pulled onto
  // the first lap where the second starts. Bound about twice the figure.
  EXPECT_LT(e_map, e_odom);
  EXPECT_LT(e_map, 0.6);
}

// livo-loop --prior-map: a site map from the first 40 s (the map's frame: that odometry's), then the
// frames from 40 s on in another odometry frame (turned 40 deg, 30 m away): LoopNode localises them and
// the exporter's trajectory_map.tum equals the Relocaliser run directly on the same inputs.
TEST(LoopNode, LocalisesInASiteMapAndTheExporterWritesTheMapFrame) {
  const std::vector<SentFrame>& fr = frames();
  const std::size_t split = 400;
  LoopCloser mapper(loopConfig());
  for (std::size_t i = 0; i < split; ++i)
    mapper.add(fr[i].odom.utime, fr[i].odom.state.pose(), [&] { return scanPoints(fr[i]); });
  mapper.finish();
  const std::string site_dir = test::tempDir("loop_node_site");
  saveSiteMap(site_dir, mapper, loopConfig().descriptor, 100.0);

  Pose other = Pose::Identity();
  other.linear() = Eigen::AngleAxisd(40.0 * M_PI / 180.0, Vec3::UnitZ()).toRotationMatrix();
  other.translation() = Vec3(30, -20, 1);
  std::vector<SentFrame> second(fr.begin() + std::ptrdiff_t(split), fr.end());
  for (SentFrame& f : second) {
    const Pose T = other * f.odom.state.pose();
    f.odom.state.R_world_imu = T.linear();
    f.odom.state.p_world_imu = T.translation();
    for (Eigen::Vector3f& p : f.scan.points) p = (other * p.cast<double>()).cast<float>();
  }

  SiteMap direct_site(site_dir, 64.0, loopConfig().descriptor);
  Relocaliser direct(loopConfig(), direct_site);
  for (const SentFrame& f : second)
    direct.add(f.odom.utime, f.odom.state.pose(), [&] { return scanPoints(f); });
  ASSERT_TRUE(direct.localised());
  MapFrameTrajectory expected;
  ASSERT_EQ(expected.apply(direct.anchors()), "");

  const std::string dir = test::tempDir("loop_node_prior");
  LcmNode lcm("memq://", "test", nullptr);
  const ChannelConfig ch;
  ExporterNode exporter(lcm, ch, MapExportConfig{}, dir, nullptr);
  SiteMap site(site_dir, 64.0, loopConfig().descriptor);
  LoopNode loop(lcm, ch, loopConfig(), nullptr, &site);
  publishFrames(lcm, ch, second);
  loop.finish();
  lcm.drain();
  exporter.finish();
  ASSERT_NE(loop.relocaliser(), nullptr);
  EXPECT_TRUE(loop.relocaliser()->localised());
  EXPECT_EQ(loop.relocaliser()->matches(), direct.matches());
  const Trajectory map = readTum(dir + "/trajectory_map.tum");
  // From 40 s the robot drives the lap's last 50 m, which the map (taken before) does not hold: it
  // localises where the lap started (about 45 s).
  ASSERT_GT(map.size(), 50u);
  double worst = 0.0, err = 0.0;
  for (const StampedPose& p : map) {
    const auto it = std::find_if(second.begin(), second.end(),
                                 [&](const SentFrame& f) { return std::abs(toSeconds(f.odom.utime) - p.t) < 1e-6; });
    ASSERT_NE(it, second.end());
    const auto T = expected.toMap(it->odom.utime, it->odom.state.pose());
    ASSERT_TRUE(T);
    worst = std::max(worst, (T->translation() - p.T_world_body.translation()).norm());
    // The map's frame is the first 40 s's odometry, which started on the truth and drifted there by at
    // most the 0.5 % of its 300 m.
    err = std::max(err, (p.T_world_body.translation() - it->truth.translation()).norm());
  }
  std::printf("second part in another frame: %zu of %zu frames in the map frame, %d anchors; exporter vs direct "
              "%.2g m; largest distance to the truth %.3f m (the map's own drift included)\n",
              map.size(), second.size(), direct.matches(), worst, err);
  EXPECT_LT(worst, 1e-5);
  // 2026-12-06: 75 of 159 frames, 21 anchors, 0.369 m at most from the truth. Bound about twice.
  EXPECT_LT(err, 0.75) << "in the map's frame (the other odometry frame is 36 m and 40 deg away)";
}

// livo-mapserver --prior-map: no site map planes before livo-loop's first correction; after it, a query
// near a mapped place inserts that place's keyframes (in the odometry frame the correction gives) and
// the answer holds their planes, with no map update from any estimator.
TEST(MapServerNode, ServesTheSiteMapsPlanesOnceLocalised) {
  const std::vector<SentFrame>& fr = frames();
  LoopCloser mapper(loopConfig());
  for (std::size_t i = 0; i < 200; ++i)
    mapper.add(fr[i].odom.utime, fr[i].odom.state.pose(), [&] { return scanPoints(fr[i]); });
  const std::string site_dir = test::tempDir("mapserver_site");
  saveSiteMap(site_dir, mapper, loopConfig().descriptor, 100.0);
  SiteMap site(site_dir, 64.0, loopConfig().descriptor);
  PriorMapSeeder seeder(site, loopConfig());

  LcmNode lcm("memq://", "test", nullptr);
  const ChannelConfig ch;
  MapService service(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
  MapServerNode server(lcm, service, ch, nullptr);
  server.setPriorMap(&seeder);
  std::vector<Submap> answers;
  lcm.subscribeStruct<livo::submap_t, Submap>(ch.submap, [&](Submap& s) { answers.push_back(s); });

  // The odometry frame of this run: the map's turned by 40 deg and 30 m away (T_map_odom its inverse).
  Pose other = Pose::Identity();
  other.linear() = Eigen::AngleAxisd(40.0 * M_PI / 180.0, Vec3::UnitZ()).toRotationMatrix();
  other.translation() = Vec3(30, -20, 1);
  const Pose at = other * fr[100].odom.state.pose();  // a mapped place, in this run's odometry frame
  auto query = [&](std::int64_t id) {
    MapQuery q;
    q.utime = fr[100].odom.utime + id;
    q.request_id = id;
    q.T_world_imu = at;
    q.radius_m = 20.0;
    const double v = VoxelMapConfig{}.voxel_size_m;  // the root voxels around the robot, down to the ground
    for (int dx = -3; dx <= 3; ++dx)
      for (int dy = -3; dy <= 3; ++dy)
        for (int dz = -5; dz <= 0; ++dz)
          q.keys.push_back(VoxelKey::fromPoint(at.translation() + Vec3(dx, dy, dz) * v, v));
    lcm.publish(ch.map_query, toMsg(q));
    lcm.drain();
  };
  query(1);
  ASSERT_EQ(answers.size(), 1u);
  EXPECT_TRUE(answers[0].planes.empty()) << "an empty map before livo-loop localised";
  EXPECT_EQ(server.counters().prior_points, 0u);

  MapCorrection c;
  c.utime = fr[100].odom.utime;
  c.T_map_odom = other.inverse();
  c.keyframes_total = 1;
  c.keyframes = {{c.utime, Pose::Identity(), Pose::Identity()}};
  lcm.publish(ch.map_correction, toMsg(c));
  lcm.drain();
  query(2);
  ASSERT_EQ(answers.size(), 2u);
  std::printf("site map served: %zu keyframes, %llu points; answer with %zu planes\n", seeder.keyframesHanded(),
              static_cast<unsigned long long>(server.counters().prior_points), answers[1].planes.size());
  EXPECT_GT(seeder.keyframesHanded(), 5u);
  EXPECT_GT(answers[1].planes.size(), 10u);
  // The planes are where the map's points are, in this run's frame: the ground under the robot.
  bool ground = false;
  for (const SubmapPlane& p : answers[1].planes)
    ground = ground || (std::abs(p.plane.normal.z()) > 0.95 && std::abs(p.plane.center.z() - (at.translation().z() - 1.8)) < 0.5);
  EXPECT_TRUE(ground) << "a level plane about 1.8 m under the sensor";
  const std::uint64_t served = server.counters().prior_points;
  query(3);
  EXPECT_EQ(server.counters().prior_points, served) << "each keyframe once";
}

TEST(LoopNode, CorrectionsOfAnotherRunAreRefusedByTheExporter) {
  const std::string dir = test::tempDir("loop_node_other");
  LcmNode lcm("memq://", "test", nullptr);
  const ChannelConfig ch;
  ExporterNode exporter(lcm, ch, MapExportConfig{}, dir, nullptr);
  MapCorrection a;
  a.keyframes_total = 1;
  a.keyframes = {{1'000'000, Pose::Identity(), Pose::Identity()}};
  lcm.publish(ch.map_correction, toMsg(a));
  a.keyframes[0].utime = 2'000'000;  // keyframe 0 at another time
  lcm.publish(ch.map_correction, toMsg(a));
  livo::map_correction_t bad = toMsg(a);
  bad.num_loops = 1;
  bad.loop_from = {0};
  bad.loop_to = {0};
  lcm.publish(ch.map_correction, bad);
  lcm.drain();
  exporter.finish();
  EXPECT_EQ(exporter.counters().at("map_corrections"), 2.0);
  EXPECT_EQ(exporter.counters().at("map_corrections_refused"), 1.0);
  EXPECT_EQ(lcm.counters().at(ch.map_correction).rejected, 1u);
  EXPECT_NE(lcm.counters().at(ch.map_correction).last_error.find("loop_from/loop_to[0]"), std::string::npos)
      << lcm.counters().at(ch.map_correction).last_error;
}
