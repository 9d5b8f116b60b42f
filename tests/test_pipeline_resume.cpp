// A pipeline that continues another one's run (FramePipeline::resume, what a restarted livo-estimator
// does with the map server's last filter state): without an outage it reproduces the uninterrupted
// run exactly; across a 1 s outage bridged by the IMU samples it stays on the ground truth; resume
// refuses once initialised. The room scenario, LiDAR-inertial (one frame per scan), in process.
// livo-test-deps: livo_sim livo_estimation livo_eval
#include "pipeline_test_util.hpp"

#include "livo/estimation/frame_pipeline.hpp"
#include "livo/estimation/in_process_map.hpp"
#include "livo/map/hybrid_map.hpp"
#include "livo/sensors/recombiner.hpp"

#include <gtest/gtest.h>

#include <sstream>

using namespace livo;

namespace {

struct Recorded {
  PipelineConfig cfg;
  std::vector<Frame> frames;
  Trajectory gt;
};

/// The room simulated for 12 s and recut into frames (one per scan), with the rig's config.
const Recorded& room() {
  static Recorded r = [] {
    Recorded out;
    sim::SimScenario sc = sim::loadScenarioFile(livo_test::scenarioPath("room"));
    sc.duration_s = 12.0;
    sim::Simulator simulator(sc);
    std::ostringstream rig;
    simulator.writeRigConfig(rig);
    ConfigFile file = ConfigFile::parse(rig.str(), "sim rig");
    out.cfg.load(file.root());
    out.cfg.preprocess.camera_enabled = false;
    out.cfg.visual_mode = VisualMode::Off;
    Recombiner rec(out.cfg.preprocess);
    Frame f;
    const auto drain = [&] {
      while (rec.nextFrame(f)) out.frames.push_back(f);
    };
    sim::SimCallbacks cb;
    cb.imu = [&](const ImuSample& s, const sim::ImuTruth& truth) {
      rec.addImu(s);
      out.gt.push_back({toSeconds(s.utime), truth.T_world_imu});
      drain();
    };
    cb.lidar = [&](const LidarScan& s) {
      rec.addScan(s);
      drain();
    };
    simulator.run(cb);
    rec.flush();
    drain();
    return out;
  }();
  return r;
}

HybridMap newMap(const PipelineConfig& cfg) { return HybridMap(cfg.mapConfig(), cfg.lio.map, cfg.visual_map); }

/// Poses of frames [from, to) through `p` against `map`.
Trajectory runFrames(FramePipeline& p, InProcessMap& map, std::size_t from, std::size_t to) {
  Trajectory t;
  for (std::size_t i = from; i < to && i < room().frames.size(); ++i) {
    const FrameResult r = p.process(room().frames[i], map);
    if (!r.lio.initialized) continue;
    t.push_back({toSeconds(room().frames[i].utime), r.lio.state.pose()});
    // The frame's result records the one filter state as the frame left it.
    EXPECT_EQ(r.lio.state.utime, p.filter().x().utime);
    EXPECT_EQ((r.lio.state.p_world_imu - p.filter().x().p_world_imu).norm(), 0.0);
    EXPECT_EQ((r.lio.P - p.filter().P()).norm(), 0.0);
  }
  return t;
}

}  // namespace

TEST(PipelineResume, WithoutAnOutageTheRunIsTheUninterruptedOne) {
  const Recorded& rec = room();
  ASSERT_GT(rec.frames.size(), 100u);
  const std::size_t k = 60;  // 6 s: initialised long before
  // Uninterrupted.
  HybridMap map_a = newMap(rec.cfg);
  InProcessMap access_a(map_a);
  FramePipeline a(rec.cfg);
  runFrames(a, access_a, 0, k);
  const Trajectory tail_a = runFrames(a, access_a, k, rec.frames.size());
  // The same first k frames, then a new pipeline continues from the state (no samples to bridge).
  HybridMap map_b = newMap(rec.cfg);
  InProcessMap access_b(map_b);
  FramePipeline b(rec.cfg);
  runFrames(b, access_b, 0, k);
  ASSERT_TRUE(b.odometry().initialized());
  FramePipeline c(rec.cfg);
  ASSERT_TRUE(c.resume(b.filter().snapshot(), {}, "the test"));
  EXPECT_NE(c.odometry().initMessage().find("resumed from the test"), std::string::npos) << c.odometry().initMessage();
  EXPECT_FALSE(c.resume(b.filter().snapshot(), {}, "again")) << "only before the first frame";
  const Trajectory tail_c = runFrames(c, access_b, k, rec.frames.size());
  ASSERT_EQ(tail_c.size(), tail_a.size());
  double worst = 0;
  for (std::size_t i = 0; i < tail_a.size(); ++i)
    worst = std::max(worst, (tail_a[i].T_world_body.translation() - tail_c[i].T_world_body.translation()).norm());
  EXPECT_EQ(worst, 0.0) << "the whole filter state is carried over";
}

TEST(PipelineResume, AcrossAnOutageTheImuBridgesIt) {
  const Recorded& rec = room();
  const std::size_t k = 60, lost = 10;  // 1 s of frames never processed
  HybridMap map = newMap(rec.cfg);
  FramePipeline before(rec.cfg);
  {
    InProcessMap access(map);
    runFrames(before, access, 0, k);
  }
  const FilterState prior = before.filter().snapshot();
  // The IMU samples after the state up to the first frame after the outage (what the map server holds).
  std::vector<ImuSample> imu;
  for (std::size_t i = k; i <= k + lost; ++i)
    for (const ImuSample& s : rec.frames[i].imu)
      if (s.utime > prior.state.utime && (imu.empty() || s.utime > imu.back().utime)) imu.push_back(s);
  // An uninterrupted pipeline on the same frames: the reference in the same world frame.
  HybridMap map_u = newMap(rec.cfg);
  InProcessMap access_u(map_u);
  FramePipeline u(rec.cfg);
  runFrames(u, access_u, 0, k + lost);
  const Trajectory tail_u = runFrames(u, access_u, k + lost, rec.frames.size());
  const auto worstApart = [&](const Trajectory& t) {
    double w = 0;
    for (std::size_t i = 0; i < t.size() && i < tail_u.size(); ++i)
      w = std::max(w, (t[i].T_world_body.translation() - tail_u[i].T_world_body.translation()).norm());
    return w;
  };
  // Resumed with the outage's samples, and (for contrast) without them: the filter then holds the
  // next frame's first sample across the whole second.
  const auto resumed = [&](const std::vector<ImuSample>& samples, HybridMap& m) {
    InProcessMap access(m);
    FramePipeline after(rec.cfg);
    EXPECT_TRUE(after.resume(prior, samples, "the test"));
    return runFrames(after, access, k + lost, rec.frames.size());
  };
  HybridMap map_blind = newMap(rec.cfg);  // the same first k frames into a second map (deterministic)
  {
    InProcessMap access_blind(map_blind);
    FramePipeline again(rec.cfg);
    runFrames(again, access_blind, 0, k);
  }
  const Trajectory tail = resumed(imu, map);
  const Trajectory blind = resumed({}, map_blind);
  ASSERT_EQ(tail.size(), tail_u.size());
  const EvalResult e = evaluate(rec.gt, tail, EvalConfig{}), eu = evaluate(rec.gt, tail_u, EvalConfig{});
  std::cout << "resumed across 1 s (" << imu.size() << " IMU samples): ATE after it " << e.ate.translation_m.rmse * 100
            << " cm (uninterrupted " << eu.ate.translation_m.rmse * 100 << " cm), at most "
            << worstApart(tail) * 100 << " cm from the uninterrupted poses; without the samples "
            << worstApart(blind) * 100 << " cm\n";
  // Measured 2026-12-07 (the LiDAR update's free-direction gain, e1fb8b1): 221 samples, ATE 0.184 cm
  // (uninterrupted 0.383 cm; 0.568 and 0.439 cm before it), at most 2.20 cm from the uninterrupted
  // poses (1.03 cm before: both runs moved, each closer to the truth); without the samples 18 m (the
  // filter diverges). Bound on the distance about twice it.
  EXPECT_LE(e.ate.translation_m.rmse, 1.5 * eu.ate.translation_m.rmse);
  EXPECT_LE(worstApart(tail), 0.045) << "no jump beyond the IMU's drift over the outage";
  EXPECT_GT(worstApart(blind), 10 * worstApart(tail)) << "the outage's samples are what bridges it";
}
