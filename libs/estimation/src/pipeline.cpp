#include "livo/estimation/pipeline.hpp"

namespace livo {

Pipeline::Pipeline(PipelineConfig cfg)
    : recombiner_(cfg.preprocess),
      map_(std::make_unique<HybridMap>(cfg.mapConfig(), cfg.lio.map, cfg.visual_map)),
      access_(std::make_unique<InProcessMap>(*map_)),
      frames_(std::move(cfg)) {}

std::size_t Pipeline::processReady(const FrameCallback& cb) {
  std::size_t n = 0;
  Frame frame;
  while (recombiner_.nextFrame(frame)) {
    const FrameResult r = frames_.process(frame, *access_);
    ++n;
    if (cb) cb(frame, r);
  }
  return n;
}

void Pipeline::insertPriorPoints(const std::vector<PointWithCov>& points) {
  if (!points.empty()) map_->lidar().insert(points);
}

}  // namespace livo
