// Shared by the estimator / map server tests: a simulated scenario recut into frames (what
// livo-preprocess publishes), with the rig config and the ground truth.
#pragma once

#include "livo/estimation/pipeline.hpp"
#include "livo/eval/evaluate.hpp"
#include "livo/sensors/recombiner.hpp"
#include "livo/sim/simulator.hpp"

#include <sstream>
#include <string>
#include <vector>

namespace livo_test {

struct SimFrames {
  livo::PipelineConfig cfg;
  std::vector<livo::Frame> frames;
  livo::Trajectory gt;
  livo::Trajectory single;  ///< the single-process Pipeline on the same data (livo-run)
  std::size_t single_visual_frames = 0;
};

inline std::string scenarioPath(const std::string& name) {
  return std::string(LIVO_SOURCE_DIR) + "/config/sim/" + name + ".yaml";
}

/// Simulates `name` for `duration_s` and recuts it into frames with the rig's preprocess config.
inline SimFrames simulateFrames(const std::string& name, double duration_s, const std::string& visual_mode) {
  livo::sim::SimScenario sc = livo::sim::loadScenarioFile(scenarioPath(name));
  sc.duration_s = duration_s;
  livo::sim::Simulator simulator(sc);
  std::ostringstream rig;
  simulator.writeRigConfig(rig);
  livo::ConfigFile file = livo::ConfigFile::parse(rig.str(), "sim rig");
  SimFrames out;
  out.cfg.load(file.root());
  out.cfg.visual_mode = livo::parseVisualMode(visual_mode);
  if (visual_mode == "off") out.cfg.preprocess.camera_enabled = false;
  livo::Recombiner rec(out.cfg.preprocess);
  livo::Pipeline pipeline(out.cfg);
  livo::Frame f;
  const auto onFrame = [&](const livo::Frame& fr, const livo::FrameResult& r) {
    if (!r.lio.initialized) return;
    out.single.push_back({livo::toSeconds(fr.utime), r.lio.state.pose()});
    out.single_visual_frames += r.visual_used;
  };
  const auto drain = [&]() {
    while (rec.nextFrame(f)) out.frames.push_back(f);
    pipeline.processReady(onFrame);
  };
  livo::sim::SimCallbacks cb;
  cb.imu = [&](const livo::ImuSample& s, const livo::sim::ImuTruth& truth) {
    rec.addImu(s);
    pipeline.addImu(s);
    out.gt.push_back({livo::toSeconds(s.utime), truth.T_world_imu});
    drain();
  };
  cb.lidar = [&](const livo::LidarScan& s) {
    rec.addScan(s);
    pipeline.addScan(s);
    drain();
  };
  if (visual_mode != "off") {
    cb.image = [&](const livo::Image& img, const livo::sim::ImageTruth&) {
      rec.addImage(img);
      pipeline.addImage(img);
      drain();
    };
  }
  simulator.run(cb);
  rec.flush();
  pipeline.flush();
  drain();
  return out;
}

inline double ateRmse(const livo::Trajectory& gt, const livo::Trajectory& est) {
  return livo::evaluate(gt, est, livo::EvalConfig{}).ate.translation_m.rmse;
}

}  // namespace livo_test
