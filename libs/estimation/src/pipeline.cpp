#include "livo/estimation/pipeline.hpp"

#include "livo/common/timing.hpp"

#include <opencv2/imgproc.hpp>

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
  if (r.lio.initialized && r.lio.n_matched > 0) {
    low_sigma_run_ = r.lio.sigma_min < cfg_.selector.degeneracy_threshold ? low_sigma_run_ + 1 : 0;
    r.degenerate = low_sigma_run_ >= cfg_.selector.degenerate_frames;
  }
  // 4-6. Frame selection, photometric update, visual map update.
  if (camera_ && frame.has_image && r.lio.initialized && r.lio.lio_ok &&
      selector_.select(r.lio.state, r.lio.sigma_min, r.degenerate)) {
    visualStep(frame, r);
  }
  // 7. Map maintenance at the frame's position: slides when due (their work spread over frames), the
  // memory cap. Visual point pointers of this frame are not used beyond this point.
  if (r.lio.initialized) r.map = map_->update(r.lio.state.p_world_imu);
  r.total_ms = watch.elapsedMs();
  ++frames_;
  return r;
}

void Pipeline::visualStep(const Frame& frame, FrameResult& r) {
  Stopwatch watch;
  const CameraModel& cam = *camera_;
  // The image at the processing scale (the camera model is already scaled).
  Image img;
  const Image* gray = &frame.image;
  if (frame.image.width != cam.width() || frame.image.height != cam.height()) {
    if (std::abs(cfg_.camera.scale - 1.0) < 1e-12 || frame.image.width != cfg_.camera.width ||
        frame.image.height != cfg_.camera.height) {
      ++images_wrong_size_;  // not the calibrated camera: never read it with this model
      return;
    }
    const cv::Mat src(frame.image.height, frame.image.width, CV_8UC1, const_cast<std::uint8_t*>(frame.image.data.data()),
                      static_cast<std::size_t>(frame.image.row_stride));
    cv::Mat dst;
    cv::resize(src, dst, cv::Size(cam.width(), cam.height()), 0, 0, cv::INTER_AREA);
    img.utime = frame.image.utime;
    img.width = dst.cols;
    img.height = dst.rows;
    img.row_stride = dst.cols;
    img.data.assign(dst.datastart, dst.dataend);
    gray = &img;
  }
  const Pose& T_imu_camera = cfg_.camera.T_imu_camera;
  NavState x = odometry_.state();
  StateCov P = odometry_.covariance();

  // Retrieval: visual points in the voxels of the current scan, one per grid cell, not occluded.
  std::vector<Vec3> scan_world;
  scan_world.reserve(r.lio.points.size());
  for (const auto& bp : r.lio.points) scan_world.push_back(x.R_world_imu * bp.p_imu + x.p_world_imu);
  // Both the local and the long-term visual maps are searched.
  const std::vector<VisualPoint*> pts = map_->pointsInView(cam, x.pose() * T_imu_camera, scan_world);

  // Photometric update, sequential after the LiDAR one at the same time stamp.
  VioUpdateResult vu;
  if (!pts.empty()) {
    vu = visualUpdate(x, P, *gray, cam, T_imu_camera, pts, cfg_.vio);
    if (vu.points_used > 0) odometry_.setState(x, P);
  }

  // Visual map at the posterior: errors, new observations, references/normals, new points.
  const Pose T_world_camera = x.pose() * T_imu_camera;
  const double gate = cfg_.vio.outlier_rms * cfg_.vio.outlier_rms;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (vu.point_rms.size() == pts.size() && vu.point_rms[i] >= 0) {
      map_->reportPhotometricError(*pts[i], vu.point_rms[i] * vu.point_rms[i], gate);
      if (map_->addObservation(*pts[i], *gray, T_world_camera, vu.point_px[i], float(x.inv_exposure), frame.utime))
        map_->refine(*pts[i]);
    }
  }
  map_->removeBadPoints();
  std::vector<NewPointCandidate> candidates;
  candidates.reserve(r.lio.matched_index.size());
  for (std::size_t k = 0; k < r.lio.matched_index.size(); ++k) {
    const BodyPoint& bp = r.lio.points[static_cast<std::size_t>(r.lio.matched_index[k])];
    NewPointCandidate c;
    c.p_world = x.R_world_imu * bp.p_imu + x.p_world_imu;
    c.normal_world = r.lio.matched_normals[k];
    c.cov_world = worldPointCovariance(x, P, bp);
    candidates.push_back(c);
  }
  std::vector<bool> occupied = map_->occupiedCells();
  if (occupied.size() != static_cast<std::size_t>(map_->gridFor(cam).size())) occupied.clear();
  r.n_new_visual_points = map_->addPoints(*gray, cam, T_world_camera, float(x.inv_exposure), frame.utime,
                                                candidates, occupied);
  selector_.markUsed(x);
  r.visual_used = true;
  r.n_visual_points = vu.points_used;
  r.vio_rms_before = vu.rms_before;
  r.vio_rms_after = vu.rms_after;
  r.lio.state = x;  // the frame's output is the posterior after the visual update
  r.lio.P = P;
  r.vio_ms = watch.elapsedMs();
}

}  // namespace livo
