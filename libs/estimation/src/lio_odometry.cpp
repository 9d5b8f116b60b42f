#include "livo/estimation/lio_odometry.hpp"

#include "livo/common/timing.hpp"
#include "livo/estimation/undistort.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/sensors/downsample.hpp"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <sstream>


namespace livo {

void LioOdometryConfig::load(const ConfigNode& root, const PreprocessConfig& pre) {
  imu.load(root.section("imu"), pre.imu_rate_hz);
  lio.load(root);
  map.load(root.section("voxel_map"));
  const ConfigNode lidar = root.section("lidar");
  lidar.require("T_imu_lidar", T_imu_lidar);
  requireMode(lidar, "model", lidar_model);
  root.section("lio").get("min_matches", min_matches);
}

LioOdometry::LioOdometry(LioOdometryConfig cfg, Esikf& filter) : cfg_(std::move(cfg)), filter_(filter), init_(cfg_.imu) {}

bool LioOdometry::initialise(const Frame& frame) {
  // Every sample of the frame: the state starts at the frame's first one and predict() propagates
  // through them all.
  for (const auto& s : frame.imu) {
    if (s.utime <= last_imu_fed_) continue;
    last_imu_fed_ = s.utime;
    init_.add(s);
  }
  if (!init_.ready()) return false;
  NavState x;
  StateCov P;
  double tilt_sigma = 0, accel_scale = 1;
  if (!init_.start(x, P, tilt_sigma, accel_scale)) return false;
  if (!frame.imu.empty()) x.utime = std::min(x.utime, frame.imu.front().utime);
  filter_.start(x, P, accel_scale);
  std::ostringstream os;
  os.precision(3);
  os << "filter started from " << cfg_.imu.init_samples << " IMU samples: gravity from their mean specific force (tilt sigma "
     << tilt_sigma * 180.0 / M_PI << " deg), accel scale " << accel_scale
     << (std::abs(accel_scale - 1.0) > 0.2 ? " (g units)" : "") << ", velocity 0 (sigma " << cfg_.imu.init_speed_sigma_mps
     << " m/s), gyro bias [" << x.bg.transpose() << "] rad/s; the LiDAR updates refine them";
  if (!cfg_.imu.ignored_keys.empty()) {
    os << "; ignored keys of the removed start rules:";
    for (const auto& k : cfg_.imu.ignored_keys) os << " " << k;
  }
  init_message_ = os.str();
  return true;
}

namespace {

/// The longest the map's first scan is gathered for (no LiDAR in use turns slower than 5 Hz; frames
/// without a finite azimuth never revisit).
constexpr double kMaxScanSeconds = 1.0;

/// 10-degree azimuth cells (about the LiDAR's z axis) that the sweep's points fall in.
std::bitset<36> azimuthCells(const LidarScan& sweep) {
  std::bitset<36> cells;
  for (const auto& pt : sweep.points) {
    const double az = std::atan2(double(pt.p_lidar.y()), double(pt.p_lidar.x()));
    if (!std::isfinite(az)) continue;
    cells.set(std::min(35, std::max(0, int((az + M_PI) / (2.0 * M_PI) * 36.0))));
  }
  return cells;
}

/// A frame comes back to directions already covered: more than half of its cells are among them.
bool revisits(const std::bitset<36>& cells, const std::bitset<36>& covered) {
  return 2 * (cells & covered).count() > cells.count();
}

}  // namespace

bool LioOdometry::resume(const FilterState& prior, std::vector<ImuSample> imu, const std::string& source) {
  if (initialized_) return false;
  filter_.start(prior.state, prior.P, prior.accel_scale, /*time_offset_prior_in_P=*/true);
  resume_imu_ = std::move(imu);
  initialized_ = true;
  map_started_ = true;  // the map holds the previous estimator's scans
  last_imu_fed_ = prior.state.utime;
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
  if (initialized_) return "initialised";
  if (init_.firstSampleTime() < 0) return "no IMU sample yet";
  return init_.status();
}

std::vector<PointWithCov> LioOdometry::scanForMap(LioFrameResult& r) {
  const std::vector<BodyPoint>& pts = r.points;
  std::vector<PointWithCov> world;
  world.reserve(pts.size());
  // The first scan defines the map's frame: its geometry relative to that frame is as exact as the
  // LiDAR; the pose's uncertainty (the start's tilt, the origin) is the state's, not the map's.
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
    r.map_started = !map_started_ || seeding_;
    map_started_ = true;
  }
  return world;
}

bool LioOdometry::predict(const Frame& frame, LioFrameResult& r) {
  r = LioFrameResult{};
  r.utime = frame.utime;
  r.n_raw_points = static_cast<int>(frame.sweep.points.size());
  Stopwatch watch;

  // 1a. The start: the filter from the first window of IMU samples (imu_init.hpp).
  if (!initialized_) {
    if (!initialise(frame)) return false;
    initialized_ = true;
    seeding_ = true;  // the map's first whole scan follows (a resumed run never comes here)
  }
  r.initialized = true;
  if (frame.utime <= filter_.x().utime) {  // a frame inside the initialisation window: nothing to estimate yet
    recordState(r);
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
  // The map starts from a whole scan: a frame cut at an
  // image time holds a wedge of a spinning LiDAR's revolution, and a map of one wedge constrains the
  // next in few directions, each from a few planes (a second frame moved 0.6 m and 3.5 deg from 39
  // matches). Until a frame comes back to directions the map's frames already cover, it is inserted
  // at its predicted pose (its points' covariance carrying the pose's uncertainty) without an update.
  if (seeding_ && !frame.sweep.points.empty()) {
    const std::bitset<36> cells = azimuthCells(frame.sweep);
    const bool back = seed_cells_.any() && revisits(cells, seed_cells_);
    if (seed_cells_.none()) seed_start_ = frame.utime;
    if (back || toSeconds(frame.utime - seed_start_) > kMaxScanSeconds) seeding_ = false;
    else seed_cells_ |= cells;
  }
  recordState(r);  // the prediction until update()
  r.lio_ms = watch.elapsedMs();
  return true;
}

void LioOdometry::update(LioFrameResult& r, const PlaneFinder& planes, WorkerPool* pool) {
  Stopwatch watch;
  // 3. Iterated point-to-plane update against the map (skipped until the map has content).
  if (map_started_ && !seeding_ && !r.points.empty()) {
    NavState x = filter_.x();
    StateCov P = filter_.P();
    const LioUpdateResult u = lidarUpdate(x, P, r.points, planes, cfg_.lio, pool);
    r.update_ran = true;
    r.n_matched = u.matched;
    r.iterations = u.iterations;
    r.rms_residual_m = u.rms_residual_m;
    r.n_covered = u.covered;
    r.nis = u.nis;
    r.correction_chi2 = u.correction_chi2;
    r.correction_m = u.correction_m;
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
