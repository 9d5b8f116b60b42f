#include "livo/estimation/pipeline.hpp"

#include "livo/common/timing.hpp"
#include "livo/estimation/visual_step.hpp"

namespace livo {

void PipelineConfig::load(const ConfigNode& root) {
  preprocess.load(root);
  lio.load(root);
  camera.load(root);
  selector.load(root);
  vio.load(root);
  visual_map.load(root.section("vio"));
  map.load(root.section("map"));
}

namespace {
HybridMapConfig hybridConfig(const PipelineConfig& cfg) {
  HybridMapConfig c = cfg.map;
  c.mode = parseMapMode(cfg.map_mode);  // throws naming the value
  return c;
}
}  // namespace

Pipeline::Pipeline(PipelineConfig cfg)
    : cfg_(std::move(cfg)),
      recombiner_(cfg_.preprocess),
      map_(std::make_unique<HybridMap>(hybridConfig(cfg_), cfg_.lio.map, cfg_.visual_map)),
      odometry_(cfg_.lio, *map_),
      selector_(cfg_.selector, parseVisualMode(cfg_.visual_mode)) {
  if (cfg_.camera.enabled) camera_ = CameraModel::create(cfg_.camera);
}

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
  r.degenerate = selector_.degenerate(r.lio.initialized && r.lio.n_matched > 0, r.lio.sigma_min);
  // 4-6. Frame selection, photometric update, visual map update. An image that is not the calibrated
  // camera's size is never read with this model: counted, and the frame stays LiDAR-inertial.
  Image scratch;
  const Image* gray = nullptr;
  if (camera_ && frame.has_image) {
    gray = processingImage(frame.image, cfg_.camera, *camera_, scratch);
    if (gray == nullptr) ++images_wrong_size_;
  }
  if (gray != nullptr && r.lio.initialized && r.lio.lio_ok &&
      selector_.select(r.lio.state, r.lio.sigma_min, r.degenerate)) {
    visualStep(frame, *gray, r);
  }
  // 7. Map maintenance at the frame's position: slides when due (their work spread over frames), the
  // memory cap. Visual point pointers of this frame are not used beyond this point.
  if (r.lio.initialized) r.map = map_->update(r.lio.state.p_world_imu);
  r.total_ms = watch.elapsedMs();
  ++frames_;
  return r;
}

void Pipeline::visualStep(const Frame& frame, const Image& gray, FrameResult& r) {
  Stopwatch watch;
  const CameraModel& cam = *camera_;
  NavState x = odometry_.state();
  StateCov P = odometry_.covariance();
  HybridVisualOps ops(*map_);  // both the local and the long-term visual maps are searched
  const VisualStepResult vs =
      runVisualStep(ops, x, P, gray, cam, cfg_.camera.T_imu_camera, cfg_.vio, frame.utime, r.lio);
  if (vs.update.points_used > 0) odometry_.setState(x, P);
  selector_.markUsed(x);
  r.visual_used = true;
  r.n_visual_points = vs.update.points_used;
  r.n_new_visual_points = vs.n_new_points;
  r.vio_rms_before = vs.update.rms_before;
  r.vio_rms_after = vs.update.rms_after;
  r.lio.state = x;  // the frame's output is the posterior after the visual update
  r.lio.P = P;
  r.vio_ms = watch.elapsedMs();
}

}  // namespace livo
