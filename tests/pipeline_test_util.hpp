// Shared by the end-to-end pipeline tests: a scenario simulated in process and run through the same
// Pipeline livo-run uses, with the rig config the simulator writes (as livo-sim --rig does), scored
// against the simulator's ground truth.
#pragma once

#include "livo/common/timing.hpp"
#include "livo/estimation/pipeline.hpp"
#include "livo/eval/evaluate.hpp"
#include "livo/sim/simulator.hpp"

#include <algorithm>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace livo_test {

inline std::string scenarioPath(const std::string& name) {
  return std::string(LIVO_SOURCE_DIR) + "/config/sim/" + name + ".yaml";
}

struct RunSummary {
  livo::Trajectory est, gt;
  livo::EvalResult eval;
  std::size_t frames = 0, degenerate_frames = 0, lio_ok_frames = 0, images = 0, visual_frames = 0;
  std::size_t lidar_failed_frames = 0;
  std::size_t frames_without_image = 0;
  double mean_sigma_min = 0.0;
  double median_lio_ms = 0.0;
  double first_pose_s = -1.0;  ///< first pose, seconds after the first simulated sample
  double max_pose_gap_s = 0.0; ///< largest step between consecutive poses
  livo::ImageCheckCounters image_counters;
  std::vector<bool> lidar_failed;  ///< per pose in `est`: its LiDAR update failed
  std::vector<livo::HealthState> health;  ///< per pose in `est`: the frame's state (health.hpp)
  double t_start = 0.0;            ///< first simulated sample, seconds
  /// camera.estimate_time_offset: (seconds after the first sample, estimate s, sigma s, whether the
  /// frame reset it to the prior) per frame.
  struct TimeOffset {
    double t, estimate, sigma;
    bool reset = false;
  };
  std::vector<TimeOffset> time_offset;
  std::size_t time_offset_resets = 0;
};

/// Optional hook that may change (or drop: return false) each image before the pipeline sees it.
using ImageEdit = std::function<bool(livo::Image&)>;

/// Simulates `sc` (for `duration_s` when > 0) and runs the pipeline on it. visual_mode "off" skips
/// rendering: one frame per scan. `threads`: PipelineConfig::threads. `tweak` may change the
/// configuration loaded from the simulator's rig before the pipeline is made.
inline RunSummary runScenario(livo::sim::SimScenario sc, double duration_s, const std::string& visual_mode = "off",
                              const ImageEdit& edit = {}, int threads = 1,
                              const std::function<void(livo::PipelineConfig&)>& tweak = {}) {
  using namespace livo;
  if (duration_s > 0) sc.duration_s = duration_s;
  sim::Simulator simulator(sc);
  std::ostringstream rig;
  simulator.writeRigConfig(rig);
  ConfigFile file = ConfigFile::parse(rig.str(), "sim rig");
  PipelineConfig cfg;
  cfg.load(file.root());
  file.checkAllKeysUsed();
  const bool camera = visual_mode != "off";
  if (!camera) cfg.preprocess.camera_enabled = false;  // LiDAR-inertial: one frame per scan
  cfg.visual_mode = parseVisualMode(visual_mode);
  cfg.threads = threads;
  if (tweak) tweak(cfg);
  Pipeline pipeline(cfg);

  RunSummary out;
  std::vector<double> lio_ms;
  double sigma_sum = 0;
  const double t_start = toSeconds(sc.startUtime());
  out.t_start = t_start;
  const auto onFrame = [&](const Frame& f, const FrameResult& r) {
    ++out.frames;
    out.frames_without_image += !f.has_image;
    if (!r.lio.initialized) return;
    const double t = toSeconds(f.utime);
    if (out.est.empty()) out.first_pose_s = t - t_start;
    else out.max_pose_gap_s = std::max(out.max_pose_gap_s, t - out.est.back().t);
    out.est.push_back({t, r.lio.state.pose()});
    out.degenerate_frames += r.degenerate;
    out.lio_ok_frames += r.lio.lio_ok;
    out.lidar_failed_frames += r.lidarFailed();
    out.lidar_failed.push_back(r.lidarFailed());
    out.health.push_back(r.health.state);
    out.images += f.has_image;
    out.visual_frames += r.visual_used;
    sigma_sum += r.lio.sigma_min;
    lio_ms.push_back(r.lio.lio_ms);
    if (r.has_time_offset)
      out.time_offset.push_back({t - t_start, r.time_offset_s, r.time_offset_sigma_s, r.reset_time_offset});
    out.time_offset_resets += r.reset_time_offset;
  };
  sim::SimCallbacks cb;
  cb.imu = [&](const ImuSample& s, const sim::ImuTruth& truth) {
    pipeline.addImu(s);
    out.gt.push_back({toSeconds(s.utime), truth.T_world_imu});
    pipeline.processReady(onFrame);
  };
  cb.lidar = [&](const LidarScan& s) {
    pipeline.addScan(s);
    pipeline.processReady(onFrame);
  };
  if (camera) {
    cb.image = [&](const Image& img, const sim::ImageTruth&) {
      Image copy = img;
      if (edit && !edit(copy)) return;
      pipeline.addImage(copy);
      pipeline.processReady(onFrame);
    };
  }
  simulator.run(cb);
  pipeline.flush();
  pipeline.processReady(onFrame);
  out.image_counters = pipeline.frames().imageCounters();
  if (!out.est.empty()) {
    out.eval = evaluate(out.gt, out.est, EvalConfig{});
    out.mean_sigma_min = sigma_sum / double(out.est.size());
    out.median_lio_ms = summarize(lio_ms).median;
  }
  std::cout << sc.source.substr(sc.source.find_last_of('/') + 1) << " (" << sc.world.kind << ") " << visual_mode << " "
            << sc.duration_s << " s: " << out.frames << " frames, ATE " << out.eval.ate.translation_m.rmse * 100
            << " cm over " << out.eval.path_length_m << " m, first pose " << out.first_pose_s << " s, max pose gap "
            << out.max_pose_gap_s << " s, degenerate " << out.degenerate_frames << ", LIO ok " << out.lio_ok_frames
            << ", LiDAR failed " << out.lidar_failed_frames << ", mean sigma_min " << out.mean_sigma_min
            << ", median LIO " << out.median_lio_ms << " ms, visual " << out.visual_frames << "/" << out.images
            << " images\n";
  return out;
}

}  // namespace livo_test
