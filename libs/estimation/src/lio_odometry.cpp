#include "livo/estimation/lio_odometry.hpp"

#include "livo/common/timing.hpp"
#include "livo/estimation/undistort.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/sensors/downsample.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>


namespace livo {

void LioOdometryConfig::load(const ConfigNode& root, const PreprocessConfig& pre) {
  imu.load(root.section("imu"), pre.imu_rate_hz);
  start.load(root.section("imu"));
  lio.load(root);
  map.load(root.section("voxel_map"));
  const ConfigNode lidar = root.section("lidar");
  lidar.require("T_imu_lidar", T_imu_lidar);
  requireMode(lidar, "model", lidar_model);
  root.section("lio").get("min_matches", min_matches);
}

LioOdometry::LioOdometry(LioOdometryConfig cfg, Esikf& filter) : cfg_(std::move(cfg)), filter_(filter) {
  start_ = std::make_unique<FilterStart>(cfg_.imu, cfg_.start, cfg_.map, cfg_.lio, cfg_.min_matches, cfg_.T_imu_lidar);
}

bool LioOdometry::resume(const FilterState& prior, std::vector<ImuSample> imu, const std::string& source) {
  if (initialized_) return false;
  filter_.start(prior.state, prior.P, prior.accel_scale, /*time_offset_prior_in_P=*/true);
  resume_imu_ = std::move(imu);
  start_.reset();
  initialized_ = true;
  map_started_ = true;  // the map holds the previous estimator's scans
  std::ostringstream os;
  os.precision(3);
  os << std::fixed << "resumed from " << source << " at t " << toSeconds(prior.state.utime) << " s (position "
     << prior.state.p_world_imu.x() << " " << prior.state.p_world_imu.y() << " " << prior.state.p_world_imu.z()
     << " m), " << resume_imu_.size() << " IMU samples to bridge the gap";
  init_message_ = os.str();
  return true;
}

void LioOdometry::propagateUpToFrame(const std::vector<ImuSample>& samples, const Frame& frame) {
  filter_.propagateBefore(samples, frame.imu.empty() ? frame.utime : frame.imu.front().utime);
}

void LioOdometry::recordState(LioFrameResult& r) const {
  r.state = filter_.x();
  r.P = filter_.P();
}

std::string LioOdometry::waitMessage() const {
  if (!initialized_) return start_ ? "waiting for " + std::to_string(cfg_.imu.init_samples) + " IMU samples (imu.init_samples)" : "resumed";
  return start_ ? start_->status() : "initialised";
}

void LioOdometry::startStep(const Frame& frame, std::vector<ImuTracePoint>& trace, LioFrameResult& r, WorkerPool* pool) {
  const FilterStart::Step st = start_->update(filter_.x(), filter_.P(), frame.sweep, trace, r.points, pool);
  r.n_points = static_cast<int>(r.points.size());
  r.n_matched = st.matched;
  r.iterations = st.iterations;
  r.rms_residual_m = st.rms_residual_m;
  r.sigma_min = st.sigma_min;
  r.matched_index = st.matched_index;
  r.matched_normals = st.matched_normals;
  r.lio_ok = st.registered;
  r.starting = !st.observed;
  if (!st.observed) return;
  std::ostringstream os;
  os.precision(3);
  os << init_message_ << ". Start observed after " << start_->frames() << " frames (" << start_->registeredFrames()
     << " registered): velocity smear " << st.smear_m * 100 << " cm over the sweep, below the range noise; speed "
     << filter_.x().v_world.norm() << " m/s";
  init_message_ = os.str();
  start_.reset();  // this frame's scan seeds the map (scanForMap)
}

std::vector<PointWithCov> LioOdometry::scanForMap(LioFrameResult& r) {
  const std::vector<BodyPoint>& pts = r.points;
  std::vector<PointWithCov> world;
  world.reserve(pts.size());
  // The first scan defines the map's frame: its geometry relative to that frame is as exact as the
  // LiDAR; the pose's uncertainty is the state's, not the map's.
  StateCov first_scan_P;
  if (!map_started_) {
    first_scan_P = filter_.P();
    first_scan_P.block<3, 3>(sidx::kRot, sidx::kRot).setZero();
    first_scan_P.block<3, 3>(sidx::kPos, sidx::kPos).setZero();
  }
  const NavState& x = filter_.x();
  const WorldPointCovariance point_cov(x, map_started_ ? filter_.P() : first_scan_P);
  for (const auto& bp : pts) {
    PointWithCov pw;
    const Vec3 q = x.R_world_imu * bp.p_imu;
    pw.p_world = q + x.p_world_imu;
    pw.cov_world = point_cov(bp, q);
    world.push_back(pw);
  }
  if (!pts.empty()) {
    r.map_started = !map_started_;
    map_started_ = true;
  }
  return world;
}

bool LioOdometry::predict(const Frame& frame, LioFrameResult& r, WorkerPool* pool) {
  r = LioFrameResult{};
  r.utime = frame.utime;
  r.n_raw_points = static_cast<int>(frame.sweep.points.size());
  Stopwatch watch;

  // 1a. The start: at once, from the first frame with imu.init_samples samples (filter_start.hpp).
  if (!initialized_) {
    NavState x;
    StateCov P;
    double accel_scale = 1.0;
    if (!start_->prior(frame, x, P, accel_scale)) return false;
    filter_.start(x, P, accel_scale);
    initialized_ = true;
    init_message_ = start_->describe();
  }
  r.initialized = true;
  if (frame.utime <= filter_.x().utime) {  // a frame at or before the state: nothing to estimate
    recordState(r);
    r.starting = start_ != nullptr;
    return false;
  }

  // 1a'. After resume(): across the outage, through the samples up to where this frame's own begin.
  if (!resume_imu_.empty()) {
    propagateUpToFrame(resume_imu_, frame);
    resume_imu_.clear();
    resume_imu_.shrink_to_fit();
  }

  // 1b. Forward propagation to the frame time, keeping the per-sample trace.
  std::vector<ImuTracePoint> trace;
  filter_.propagate(frame.imu, frame.utime, &trace);

  // 1c. Undistort + downsample the sweep, with per-point covariances.
  r.points = prepareScan(frame.sweep, trace, cfg_.T_imu_lidar, cfg_.lio);
  r.n_points = static_cast<int>(r.points.size());
  // 1d. While starting: the start's registration against its own map (the odometry's map waits).
  if (start_) startStep(frame, trace, r, pool);
  recordState(r);  // the prediction until update(); while starting, the start's posterior
  r.lio_ms = watch.elapsedMs();
  return true;
}

void LioOdometry::update(LioFrameResult& r, const PlaneFinder& planes, WorkerPool* pool) {
  Stopwatch watch;
  // 3. Iterated point-to-plane update against the map (skipped until the map has content).
  if (map_started_ && !r.points.empty()) {
    NavState x = filter_.x();
    StateCov P = filter_.P();
    const LioUpdateResult u = lidarUpdate(x, P, r.points, planes, cfg_.lio, pool);
    r.n_matched = u.matched;
    r.iterations = u.iterations;
    r.rms_residual_m = u.rms_residual_m;
    r.sigma_min = degeneracySigmaMin(u.matched_normals);
    r.matched_index = u.matched_index;
    r.matched_normals = u.matched_normals;
    if (u.matched >= cfg_.min_matches) {
      filter_.x() = x;
      filter_.P() = P;
      r.lio_ok = true;
    }
  }
  r.lio_ms += watch.elapsedMs();
  recordState(r);
}

}  // namespace livo
