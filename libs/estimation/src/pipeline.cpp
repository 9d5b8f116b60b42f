#include "livo/estimation/pipeline.hpp"

#include "livo/common/timing.hpp"

namespace livo {

void PipelineConfig::load(const ConfigNode& root) {
  preprocess.load(root);
  lio.load(root);
  camera.load(root);
  selector.load(root);
}

Pipeline::Pipeline(PipelineConfig cfg)
    : cfg_(std::move(cfg)), recombiner_(cfg_.preprocess), odometry_(cfg_.lio) {}

std::size_t Pipeline::processReady(const FrameCallback& cb) {
  std::size_t n = 0;
  Frame frame;
  while (recombiner_.nextFrame(frame)) {
    const FrameResult r = processFrame(frame);
    ++n;
    if (cb) cb(frame, r);
  }
  return n;
}

FrameResult Pipeline::processFrame(const Frame& frame) {
  Stopwatch watch;
  FrameResult r;
  // 1-2. Propagate, undistort, iterated LiDAR update, map insertion.
  r.lio = odometry_.process(frame);
  // 3. Degeneracy: sigma_min of the matched normals below the threshold for several frames in a row.
  if (r.lio.initialized && r.lio.n_matched > 0) {
    low_sigma_run_ = r.lio.sigma_min < cfg_.selector.degeneracy_threshold ? low_sigma_run_ + 1 : 0;
    r.degenerate = low_sigma_run_ >= cfg_.selector.degenerate_frames;
  }
  r.total_ms = watch.elapsedMs();
  ++frames_;
  return r;
}

}  // namespace livo
