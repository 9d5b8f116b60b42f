#include "livo/estimation/frame_pipeline.hpp"

#include "livo/common/timing.hpp"
#include "livo/estimation/scan_registration.hpp"
#include "livo/estimation/visual_step.hpp"
#include "livo/map/frustum_keys.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

namespace livo {

void PipelineConfig::load(const ConfigNode& root) {
  // Each key is read and checked once, by the config of its section; a key two parts need is read
  // by the first loaded and handed to the other (imu.rate_hz, camera.enabled: the preprocessing's;
  // the camera's noise, rate and time offset keys: the camera's, for the photometric update).
  preprocess.load(root);
  lio.load(root, preprocess);
  camera.load(root, preprocess.camera_enabled);
  selector.load(root);
  vio.load(root);
  vio.takeCamera(camera);
  visual_map.load(root.section("vio"));
  map.load(root.section("map"));
  health.load(root.section("health"));
}

HybridMapConfig PipelineConfig::mapConfig() const {
  HybridMapConfig c = map;
  c.mode = map_mode;
  return c;
}

FramePipeline::FramePipeline(PipelineConfig cfg)
    : cfg_(std::move(cfg)),
      filter_(cfg_.lio.imu),
      lio_(cfg_.lio, filter_),
      selector_(cfg_.selector, cfg_.visual_mode),
      image_check_(cfg_.vio.pixel_noise),
      health_(cfg_.health) {
  if (cfg_.camera.enabled) {
    camera_ = CameraModel::create(cfg_.camera);
    vignetting_ = VignettingCorrection(cfg_.camera.vignetting, camera_->width(), camera_->height(), camera_->cx(),
                                       camera_->cy());
  }
  if (cfg_.threads != 1) pool_ = std::make_unique<WorkerPool>(cfg_.threads);  // throws naming a bad count
}

FrameResult FramePipeline::process(const Frame& frame, MapAccess& map) {
  Stopwatch watch;
  FrameResult r;
  Image scratch;
  const Image* gray = frameImage(frame, scratch, r);
  // 1. Initialisation, propagation, undistortion, downsampling (nothing to estimate before the IMU
  // is initialised or inside its window).
  if (lio_.predict(frame, r.lio)) {
    r.repeated_sweep = repeatsLastSweep(frame.sweep);
    if (r.repeated_sweep) {  // no information in it: the frame goes on without the LiDAR
      r.lio.points.clear();
      r.lio.n_points = 0;
    }
    // 2-3. The planes around the predicted scan, the iterated LiDAR update, the scan into the map.
    const PlaneFinder& planes = map.planesFor(frame, r.lio);
    lidarStep(map, planes, r);
    // 4. Degeneracy: sigma_min of the matched normals below the threshold for several frames in a
    // row, or a LiDAR update that failed (the camera is then the only exteroceptive sensor left).
    // A map existed around the scan and the update failed.
    r.lidar_failed = lio_.mapStarted() && !r.lio.lio_ok && !r.lio.map_started && !r.map_seeded;
    r.degenerate = selector_.degenerate(r.lio.n_matched > 0, r.lio.sigma_min) || r.lidar_failed;
    // 5-6. Frame selection (on the covariance after the LiDAR update); on a selected image the
    // photometric update and the visual map changes.
    if (gray != nullptr && selector_.select(r.lio.state, r.lio.P, r.lio.sigma_min, r.degenerate))
      visualStep(frame, *gray, map, r, r.lidar_failed);
  }
  // 7. The frame's end at its final state: slides and the memory cap in process, the update message
  // to the map server. Visual point pointers of this frame are not used beyond this point.
  healthStep(frame, map, r);
  if (r.lio.initialized) {
    r.lio.state = filter_.x();  // the frame's output: the filter after every update of this frame
    r.lio.P = filter_.P();
    const MapFrameReport report = map.finishFrame(frame, r.lio.state);
    r.map = report.update;
    r.link = report.link;
  }
  if (cfg_.vio.estimate_time_offset && r.lio.initialized && filter_.timeOffsetPriorSet()) {
    r.has_time_offset = true;
    r.time_offset_s = cfg_.preprocess.camera_time_offset_s + r.lio.state.time_offset_s;
    r.time_offset_sigma_s = std::sqrt(std::max(0.0, r.lio.P(sidx::kTimeOffset, sidx::kTimeOffset)));
  }
  r.total_ms = watch.elapsedMs();
  return r;
}

const Image* FramePipeline::frameImage(const Frame& frame, Image& scratch, FrameResult& r) {
  if (!camera_) return nullptr;
  const auto fail = [&](ImageStatus s) -> const Image* {
    r.image = s;
    image_counters_.count(s);
    return nullptr;
  };
  if (!frame.has_image) return cfg_.preprocess.camera_enabled ? fail(ImageStatus::Missing) : nullptr;
  const Image& img = frame.image;
  const Image* gray = &img;
  if (img.width != camera_->width() || img.height != camera_->height()) {
    // The calibrated size with a processing scale: resized; any other size is not the calibrated
    // camera's and is never read with this model.
    if (std::abs(cfg_.camera.scale - 1.0) < 1e-12 || img.width != cfg_.camera.width || img.height != cfg_.camera.height)
      return fail(ImageStatus::WrongSize);
    const cv::Mat src(img.height, img.width, CV_8UC1, const_cast<std::uint8_t*>(img.data.data()),
                      static_cast<std::size_t>(img.row_stride));
    cv::Mat dst;
    cv::resize(src, dst, cv::Size(camera_->width(), camera_->height()), 0, 0, cv::INTER_AREA);
    scratch.utime = img.utime;
    scratch.width = dst.cols;
    scratch.height = dst.rows;
    scratch.row_stride = dst.cols;
    scratch.data.assign(dst.datastart, dst.dataend);
    gray = &scratch;
  }
  const ImageStatus s = image_check_.check(*gray);  // on the camera's own values (black, saturated, frozen)
  if (s != ImageStatus::Ok) return fail(s);
  if (vignetting_.active()) {
    vignetting_.apply(*gray, scratch);
    gray = &scratch;
  }
  return gray;
}

void FramePipeline::lidarStep(MapAccess& map, const PlaneFinder& planes, FrameResult& r) {
  lio_.update(r.lio, planes, pool_.get());
  // Only a registered scan goes into the map: a failed update would insert the scan where the IMU
  // alone put it. Except where the map cannot match the scan (the first scan, new territory, an
  // empty map server, a young map whose voxels hold no planes yet: a sparse LiDAR needs several
  // scans before they do): there the scan seeds the map at the predicted pose, its points' covariance
  // carrying the pose's uncertainty, and the frame is no LiDAR failure.
  if (r.lio.points.empty()) return;
  if (lio_.mapStarted() && !r.lio.lio_ok && !lio_.seedingMap()) {
    if (map.holdsAround(r.lio, cfg_.lio.min_matches)) return;
    r.map_seeded = true;
  }
  // With health.recover, a lost filter's scans stay out of the map (they would write the error into
  // it, and the recovery would register against them). Without it the checks only observe: keeping
  // inconsistent scans out starved the map of a start in motion (stress scenarios: 2.3 -> 3.6 cm, and
  // 1.6 cm -> 3.9 m where every check fired at the start).
  if (cfg_.health.recover && health_.lost()) {
    r.scan_withheld = true;
    return;
  }
  Stopwatch map_watch;
  map.insertScan(lio_.scanForMap(r.lio));
  r.lio.map_ms = map_watch.elapsedMs();
}

void FramePipeline::visualStep(const Frame& frame, const Image& gray, MapAccess& map, FrameResult& r,
                               bool lidar_failed) {
  Stopwatch watch;  // the step's own work: the map's answer (map.visualMap) is not in vio_ms
  // Without a registered scan, the visual points come from the voxels the camera sees (up to the
  // LiDAR's range: visual points are made from LiDAR points), new ones from ray casting into the
  // map's planes.
  NoScanRetrieval no_scan;
  if (lidar_failed) {
    no_scan.max_depth_m = cfg_.preprocess.max_range_m;
    no_scan.ray_step_m = 0.5 * cfg_.lio.map.voxel_size_m;
    no_scan.min_depth_m = cfg_.visual_map.min_depth_m;
    no_scan.frustum_keys =
        frustumVoxelKeys(*camera_, r.lio.state.pose() * cfg_.camera.T_imu_camera, cfg_.visual_map.voxel_size_m,
                         cfg_.visual_map.grid_cell_px, cfg_.visual_map.min_depth_m, no_scan.max_depth_m);
  }
  const double keys_ms = watch.elapsedMs();
  const FrameVisualMap visual = map.visualMap(frame, r.lio.state, lidar_failed ? &no_scan.frustum_keys : nullptr);
  if (visual.visual == nullptr) return;  // no visual update without the map's points
  watch.restart();
  // The update acts on the filter in place; the covariance before it is the selector's reference.
  const StateCov P_before = filter_.P();
  // The camera's time offset t_d: its prior at the first visual frame after a start, reset to it when
  // the estimate leaves 3 prior sigmas (never left to pull the pose).
  if (cfg_.vio.estimate_time_offset && !filter_.timeOffsetPriorSet()) filter_.setTimeOffsetPrior(cfg_.vio.time_offset_sigma_s);
  CaptureMotion motion;  // the body rate at the image: the last IMU sample of the frame, bias removed
  if (!frame.imu.empty()) motion.omega_imu = frame.imu.back().gyro - filter_.x().bg;
  const VisualStepResult vs = runVisualStep(visual, filter_.x(), filter_.P(), gray, *camera_, cfg_.camera.T_imu_camera,
                                            cfg_.vio, frame.utime, r.lio, lidar_failed ? &no_scan : nullptr, pool_.get(),
                                            motion);
  if (cfg_.vio.estimate_time_offset && !(std::abs(filter_.x().time_offset_s) <= 3.0 * cfg_.vio.time_offset_sigma_s)) {
    filter_.setTimeOffsetPrior(cfg_.vio.time_offset_sigma_s);
    r.reset_time_offset = true;
    ++time_offset_resets_;
  }
  selector_.markUsed(filter_.x(), P_before, filter_.P());
  r.visual_used = true;
  r.n_visual_points = vs.update.points_used;
  r.n_new_visual_points = vs.n_new_points;
  r.n_longterm_visual_points = vs.n_longterm_used;
  r.vio_rms_before = vs.update.rms_before;
  r.vio_rms_after = vs.update.rms_after;
  r.vio_ms = keys_ms + watch.elapsedMs();
}

HealthInputs FramePipeline::healthInputs(const FrameResult& r) const {
  HealthInputs h;
  h.utime = r.lio.utime;
  h.initialized = r.lio.initialized;
  h.update_ran = r.lio.update_ran;
  h.n_matched = r.lio.n_matched;
  h.n_covered = r.lio.n_covered;
  h.min_matches = cfg_.lio.min_matches;
  h.correction_chi2 = r.lio.correction_chi2;
  h.correction_m = r.lio.correction_m;
  h.plane_sigma_m = std::sqrt(cfg_.lio.lio.range_noise_m * cfg_.lio.lio.range_noise_m + cfg_.lio.map.min_eigen_value);
  h.lidar_failed = r.lidar_failed;
  h.repeated_sweep = r.repeated_sweep;
  h.visual_used = r.visual_used;
  if (r.lio.initialized) h.speed_mps = filter_.x().v_world.norm();
  return h;
}

bool FramePipeline::repeatsLastSweep(const LidarScan& sweep) {
  // A fingerprint of the sweep's points as a set (a sum of per-point hashes of the coordinates' and
  // intensity's bits: a frame cut at image times from a repeated scan holds the same points in
  // another order). A real sweep never repeats to the bit (range noise); a frozen driver's does.
  const auto bits = [](float v) {
    std::uint32_t u;
    std::memcpy(&u, &v, sizeof u);
    return std::uint64_t(u);
  };
  std::uint64_t sum = 0;
  for (const auto& p : sweep.points) {
    const std::uint64_t a = bits(p.p_lidar.x()) | bits(p.p_lidar.y()) << 32;
    const std::uint64_t b = bits(p.p_lidar.z()) | bits(p.intensity) << 32;
    std::uint64_t h = a * 0x9E3779B97F4A7C15ull ^ (b + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
    h ^= h >> 29;
    sum += h;
  }
  const bool repeat = !sweep.points.empty() && sum == last_sweep_hash_ && sweep.points.size() == last_sweep_size_;
  last_sweep_hash_ = sum;
  last_sweep_size_ = sweep.points.size();
  return repeat;
}

void FramePipeline::healthStep(const Frame& frame, MapAccess& map, FrameResult& r) {
  r.health = health_.assess(healthInputs(r));
  if (r.health.state == HealthState::Ok && cfg_.health.recover) {  // only the recovery reads them
    trusted_.push_back(Trusted{filter_.x(), filter_.P()});
    while (trusted_.size() > 1 && toSeconds(trusted_.back().x.utime - trusted_.front().x.utime) > 2.0) trusted_.pop_front();
  }
  if (r.health.state == HealthState::Lost && cfg_.health.recover) recover(frame, map, r);
}

bool FramePipeline::recover(const Frame& frame, MapAccess& map, FrameResult& r) {
  const auto say = [&r](const std::string& what) { r.health.reason += (r.health.reason.empty() ? "" : "; ") + what; };
  const Utime window = Utime(std::llround(cfg_.health.window_s * 1e6));
  const Trusted* trusted = nullptr;
  for (auto it = trusted_.rbegin(); it != trusted_.rend() && trusted == nullptr; ++it)
    if (it->x.utime <= health_.lostSince() - window) trusted = &*it;
  if (trusted == nullptr && !trusted_.empty()) trusted = &trusted_.front();  // the oldest kept
  if (trusted == nullptr || static_cast<int>(r.lio.points.size()) < cfg_.lio.min_matches) return false;
  if (last_recovery_try_ >= 0 && frame.utime - last_recovery_try_ < window) return false;
  last_recovery_try_ = frame.utime;
  // Where to search: the last trusted pose carried on at its velocity (no later estimate is trusted),
  // the rotation the gyro integrated since; the cube grows by half the distance travelled since.
  const NavState& xt = trusted->x;
  const NavState xc = filter_.x();  // a copy: the restart below replaces the filter's
  const double dt = toSeconds(frame.utime - xt.utime);
  const Vec3 guess = xt.p_world_imu + xt.v_world * dt;
  SearchBounds bounds;
  bounds.translation_m = std::clamp(1.0 + 0.5 * xt.v_world.norm() * dt, 1.0, 10.0);
  bounds.yaw_rad = 30.0 * M_PI / 180.0;
  bounds.tilt_rad = 10.0 * M_PI / 180.0;
  LioFrameResult probe;  // the map's planes around the guess (the map server: a query there)
  probe.state = xc;
  probe.state.p_world_imu = guess;
  probe.points = r.lio.points;
  const PlaneFinder& planes = map.planesFor(frame, probe);
  const ScanRegistrationConfig rc = ScanRegistrationConfig::from(cfg_.lio.lio, cfg_.lio.map, cfg_.lio.min_matches);
  SearchMap search(rc);
  search.addPlanes(planes, guess, bounds.translation_m + cfg_.preprocess.max_range_m);
  const ScanRegistration reg(rc);
  NavState init = xc;
  init.p_world_imu = guess;
  const ScanRegistrationResult res = reg.align(r.lio.points, planes, search, init.pose(), bounds);
  std::ostringstream os;
  os.precision(3);
  if (!res.success || res.search_ambiguous) {
    os << "recovery " << (res.success ? "ambiguous (the map tells several poses apart little)" : "failed: " + res.reason);
    say(os.str());
    return false;
  }
  // The restart: the registered pose, the trusted velocity and biases with the start's sigmas.
  NavState x = xc;
  x.R_world_imu = res.T_world_body.rotation();
  x.p_world_imu = res.T_world_body.translation();
  x.v_world = xt.v_world;
  x.bg = xt.bg;
  x.ba = xt.ba;
  x.g_world = xt.g_world;  // a diverging filter bends its gravity estimate too
  StateCov P = trusted->P;
  const auto block = [&P](int at, double sigma) {
    P.middleRows<3>(at).setZero();
    P.middleCols<3>(at).setZero();
    P.block<3, 3>(at, at) = sigma * sigma * Mat3::Identity();
  };
  block(sidx::kRot, 1.0 * M_PI / 180.0);
  block(sidx::kPos, 0.05);
  block(sidx::kVel, cfg_.lio.imu.init_speed_sigma_mps);  // the trusted velocity is a guess: the start's sigma
  filter_.start(x, P, filter_.accelScale(), /*time_offset_prior_in_P=*/true);
  health_.recovered(frame.utime);
  trusted_.clear();
  os << "recovered: the scan registered against the map " << (x.p_world_imu - xc.p_world_imu).norm()
     << " m from the lost estimate (" << res.matched << " points matched)";
  r.health.reason = os.str();
  r.health.state = HealthState::Degraded;
  ++recoveries_;
  return true;
}

}  // namespace livo
