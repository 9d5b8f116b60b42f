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
  motion_init.load(root.section("imu"));
  lio.load(root);
  map.load(root.section("voxel_map"));
  const ConfigNode lidar = root.section("lidar");
  lidar.require("T_imu_lidar", T_imu_lidar);
  requireMode(lidar, "model", lidar_model);
  root.section("lio").get("min_matches", min_matches);
}

LioOdometry::LioOdometry(LioOdometryConfig cfg, Esikf& filter) : cfg_(std::move(cfg)), filter_(filter), init_(cfg_.imu) {
  motion_ = std::make_unique<MotionInitializer>(cfg_.imu, cfg_.motion_init, cfg_.map, cfg_.lio, cfg_.min_matches,
                                                cfg_.T_imu_lidar);
}

LioOdometry::InitStep LioOdometry::initialise(const Frame& frame) {
  for (const auto& s : frame.imu) {
    if (s.utime <= last_imu_fed_) continue;
    last_imu_fed_ = s.utime;
    // The rest of the frame's samples are propagated below (imu.start: filter takes them all).
    if (init_.add(s) && !cfg_.imu.start_filter) break;
  }
  if (cfg_.imu.start_filter) {  // the coarse start once one window of samples is in
    motion_.reset();
    const double window_s = double(cfg_.imu.init_samples - 1) / cfg_.imu.rate_hz;
    const bool window = init_.firstSampleTime() >= 0 && toSeconds(last_imu_fed_ - init_.firstSampleTime()) >= window_s;
    return window && initCoarse(frame) ? InitStep::Coarse : InitStep::Waiting;
  }
  // The motion initialiser sees every frame from the first one: it confirms rest, or takes over.
  const Frame* scan = completeScan(frame);
  const bool motion_converged = scan ? motion_->process(*scan) : motion_->converged();
  const bool deadline = init_.firstSampleTime() >= 0 &&
                        toSeconds(frame.utime - init_.firstSampleTime()) >= cfg_.imu.deadlineSeconds();
  if (init_.done()) {
    switch (confirmRest(frame)) {
      case Rest::Confirmed:
      case Rest::Unconfirmable: initAtRest(frame); return InitStep::AtRest;
      case Rest::Moved: init_.reject(); break;  // constant velocity looked like rest to the IMU
      case Rest::Unknown:
        if (!deadline) return InitStep::Waiting;
        initAtRest(frame);  // the deadline: the IMU's decision stands
        return InitStep::AtRest;
    }
  }
  // From motion, once the static search has given up (a static window observes the gyro bias).
  if (motion_converged && init_.noStaticWindow()) {
    NavState x;
    StateCov P;
    motion_->takeOver(x, P);
    filter_.start(x, P, motion_->accelScale());
    std::ostringstream os;
    os << "no static window within " << cfg_.imu.init_static_wait_s << " s" << (rest_rejections_ ? " (IMU windows that looked static were moving, said the LiDAR)" : "")
       << "; " << motion_->describe();
    init_message_ = os.str();
    return InitStep::InMotion;
  }
  if (deadline && initCoarse(frame)) return InitStep::Coarse;
  return InitStep::Waiting;
}

namespace {

/// The longest a scan is joined for (no LiDAR in use turns slower than 5 Hz; frames without a finite
/// azimuth never revisit).
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

const Frame* LioOdometry::completeScan(const Frame& frame) {
  // A frame cut at an image time holds only part of a spinning LiDAR's revolution (a wedge of
  // 120 degrees with a camera at three times the LiDAR's rate), and a wedge constrains the pose in
  // few directions: the motion initialiser registers whole scans. Consecutive frames are joined until
  // the next one comes back to directions the joined ones already cover (more than half of its cells):
  // one revolution of a spinning LiDAR, one frame of a Livox (every frame covers the whole field of view).
  // A joined scan longer than kMaxScanSeconds is handed over whatever it covers.
  const std::bitset<36> cells = azimuthCells(frame.sweep);
  const bool first = !pending_scan_.has_value();
  const bool back = !first && revisits(cells, pending_cells_);
  const bool too_long = !first && toSeconds(frame.utime - pending_scan_->sweep.utime) > kMaxScanSeconds;
  if (!first && !back && !too_long && !frame.sweep.points.empty()) {
    Frame& p = *pending_scan_;
    const float shift = float(toSeconds(frame.sweep.utime - p.sweep.utime));
    for (LidarPoint pt : frame.sweep.points) {
      pt.time_offset_s += shift;
      p.sweep.points.push_back(pt);
    }
    for (const auto& s : frame.imu)
      if (p.imu.empty() || s.utime > p.imu.back().utime) p.imu.push_back(s);
    p.utime = frame.utime;
    pending_cells_ |= cells;
    return nullptr;
  }
  // The joined frames are a whole scan: hand them over, this frame starts the next one.
  complete_scan_ = std::move(pending_scan_);
  pending_scan_.emplace();  // the frame without its image
  pending_scan_->utime = frame.utime;
  pending_scan_->sweep_start_utime = frame.sweep_start_utime;
  pending_scan_->imu = frame.imu;
  pending_scan_->sweep = frame.sweep;
  pending_cells_ = cells;
  return complete_scan_ ? &*complete_scan_ : nullptr;
}

bool LioOdometry::initCoarse(const Frame& frame) {
  NavState x;
  double tilt_sigma = 0, accel_scale = 1;
  StateCov P;
  if (!init_.coarseState(x, P, tilt_sigma, accel_scale)) return false;
  const std::string waited = waitMessage();
  // The velocity of the LiDAR fixes when there are two (else rest), in the coarse world frame.
  Vec3 v_body = Vec3::Zero();
  const bool have_v = motion_ && motion_->velocityBody(v_body);
  // Gravity's direction in the map frame is estimated where the LiDAR constrains every direction of
  // the motion (the accelerations that reveal it are observed); along a wall or a corridor it would
  // wander with the unconstrained translation, and the tilt stays in the attitude.
  free_gravity_ = motion_ && motion_->weakestShare() >= MotionInitializer::kConstrainedShare;
  x.v_world = x.R_world_imu * v_body;
  // State at the start of this frame's samples (predict() propagates through them).
  if (!frame.imu.empty()) x.utime = std::min(x.utime, frame.imu.front().utime);
  P.block<3, 3>(sidx::kPos, sidx::kPos) = Mat3::Identity() * 1e-6;  // the origin
  // Speed: wide. Fixes that agree over two intervals may still slide together along a degenerate
  // direction (a wall, a corridor's axis), and without them the rig may move at a run's or a drone's
  // speed; a tight prior there holds a wrong velocity against the camera (random rigs 10 and 12 of the
  // matrix: 2 m/s instead of 0.3 took rig 10 from 53 m to 0.11 m ATE over 12 s).
  const double sv = std::max(2.0, 0.5 * v_body.norm());
  P.block<3, 3>(sidx::kVel, sidx::kVel) = Mat3::Identity() * sv * sv;
  filter_.start(x, P, accel_scale);
  motion_.reset();
  std::ostringstream os;
  os.precision(3);
  os << "coarse start at the " << cfg_.imu.deadlineSeconds() << " s deadline (" << waited << "): gravity from the mean specific force (tilt sigma "
     << tilt_sigma * 180.0 / M_PI << " deg), velocity " << (have_v ? "of the last LiDAR fixes" : "0") << " (sigma " << sv
     << " m/s); the filter refines both";
  init_message_ = os.str();
  return true;
}

bool LioOdometry::resume(const FilterState& prior, std::vector<ImuSample> imu, const std::string& source) {
  if (initialized_) return false;
  filter_.start(prior.state, prior.P, prior.accel_scale, /*time_offset_prior_in_P=*/true);
  resume_imu_ = std::move(imu);
  motion_.reset();
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
  std::string m = init_.status();
  if (motion_) m += "; " + motion_->status();
  return m;
}

LioOdometry::Rest LioOdometry::confirmRest(const Frame& frame) {
  // Rest: the registered positions since the window began stay within 5 sigma of a LiDAR return
  // (a whole scan registers far better than one return).
  bool known = false;
  const bool rest = motion_->atRestSince(init_.windowStart(), 5.0 * cfg_.lio.range_noise_m, known);
  if (known) {
    if (rest) return Rest::Confirmed;
    ++rest_rejections_;
    return Rest::Moved;
  }
  // Without LiDAR registrations for long (no returns, no overlap) the IMU's decision stands.
  const double waited_s = toSeconds(frame.utime - init_.firstSampleTime());
  return waited_s > 3.0 * cfg_.imu.init_static_wait_s ? Rest::Unconfirmable : Rest::Unknown;
}

void LioOdometry::initAtRest(const Frame& frame) {
  filter_.start(init_.initialState(), init_.initialCovariance(), init_.accelScale());
  // Through the samples after the chosen window.
  propagateUpToFrame(init_.samplesAfterWindow(), frame);
  motion_.reset();
  init_message_ = init_.describe();
}

std::vector<PointWithCov> LioOdometry::scanForMap(LioFrameResult& r) {
  const std::vector<BodyPoint>& pts = r.points;
  std::vector<PointWithCov> world;
  world.reserve(pts.size());
  // The first scan defines the map's frame: its geometry relative to that frame is as exact as the
  // LiDAR; the pose's uncertainty (a coarse start's tilt, the origin) is the state's, not the map's.
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
    if (!map_started_ && free_gravity_) {
      mapFrameFromFirstScan();
      r.P = filter_.P();
    }
    map_started_ = true;
  }
  return world;
}

bool LioOdometry::predict(const Frame& frame, LioFrameResult& r) {
  r = LioFrameResult{};
  r.utime = frame.utime;
  r.n_raw_points = static_cast<int>(frame.sweep.points.size());
  Stopwatch watch;

  // 1a. Initialisation: at rest (gravity, gyro bias, g units) or, without a static window, from motion.
  if (!initialized_) {
    const InitStep step = initialise(frame);
    if (step == InitStep::Waiting) return false;
    initialized_ = true;
    pending_scan_.reset();
    complete_scan_.reset();
    seeding_ = !map_started_ || step == InitStep::InMotion;
    if (step == InitStep::InMotion) {
      // The motion initialiser's state is at the end of the last whole scan, before this frame (a scan
      // is known whole when the next frame arrives): this frame is propagated and registered as any
      // other, and its scan seeds the odometry's map.
      motion_.reset();
      map_started_ = false;
    }
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
  // The map starts from a whole scan (the start's rule for its fixes, completeScan): a frame cut at an
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

void LioOdometry::mapFrameFromFirstScan() {
  // The first scan defines the map's frame at the estimated attitude: relative to the map, that
  // attitude is exact, and the attitude's tilt uncertainty becomes gravity's (and the velocity's)
  // direction in the map frame. With R_true = R Exp(dtheta), the map frame is the world rotated by
  // Exp(R dtheta), so a vector u of the world reads u + [u]x R dtheta in the map frame. Without this
  // a coarse start's tilt error (up to 15 deg) would stay in the map as a wrong gravity that only the
  // accelerometer bias could absorb, and only until the rig turns (a car accelerating at 2 m/s^2 at
  // the deadline, random rig 5's street: 14.7 m ATE over 12 s without, 4 cm with).
  using namespace sidx;
  StateCov T = StateCov::Identity();
  T.block<3, 3>(kRot, kRot).setZero();
  const NavState& x = filter_.x();
  StateCov& P = filter_.P();
  T.block<3, 3>(kGrav, kRot) = hat(x.g_world) * x.R_world_imu;
  T.block<3, 3>(kVel, kRot) = hat(x.v_world) * x.R_world_imu;
  T.block<3, 3>(kPos, kRot) = hat(x.p_world_imu) * x.R_world_imu;
  P = T * P * T.transpose();
  P.block<3, 3>(kRot, kRot) += Mat3::Identity() * 1e-10;  // positive definite
}

}  // namespace livo
