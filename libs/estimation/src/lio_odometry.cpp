#include "livo/estimation/lio_odometry.hpp"

#include "livo/common/timing.hpp"
#include "livo/estimation/undistort.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/sensors/downsample.hpp"

#include <stdexcept>

namespace livo {

void LioOdometryConfig::load(const ConfigNode& root) {
  imu.load(root.section("imu"));
  lio.load(root);
  map.load(root.section("voxel_map"));
  const ConfigNode lidar = root.section("lidar");
  lidar.require("T_imu_lidar", T_imu_lidar).require("model", lidar_model);
  lidar.check(lidar_model == "avia" || lidar_model == "mid360" || lidar_model == "spinning32" ||
                  lidar_model == "generic",
              "model", "must be avia, mid360, spinning32 or generic, got '" + lidar_model + "'");
  root.section("lio").get("min_matches", min_matches);
}

namespace {
HybridMapConfig globalMapConfig() {
  HybridMapConfig c;
  c.mode = MapMode::Global;
  return c;
}
}  // namespace

LioOdometry::LioOdometry(LioOdometryConfig cfg)
    : cfg_(std::move(cfg)),
      init_(cfg_.imu),
      own_map_(std::make_unique<HybridMap>(globalMapConfig(), cfg_.map, VisualMapConfig{})),
      map_(own_map_.get()) {}

LioOdometry::LioOdometry(LioOdometryConfig cfg, HybridMap& map) : cfg_(std::move(cfg)), init_(cfg_.imu), map_(&map) {}

LioOdometry::LioOdometry(LioOdometryConfig cfg, RemoteMapTag) : cfg_(std::move(cfg)), init_(cfg_.imu), map_(nullptr) {}

std::vector<BodyPoint> LioOdometry::preparePoints(const LidarScan& sweep,
                                                  const std::vector<ImuTracePoint>& trace) const {
  // Undistort every point to the frame time, then downsample in the IMU frame (FAST-LIVO2 order).
  std::vector<LidarPoint> undistorted = undistortToEnd(sweep, trace, cfg_.T_imu_lidar);
  if (cfg_.lio.downsample_m > 0) undistorted = voxelDownsample(undistorted, static_cast<float>(cfg_.lio.downsample_m));
  // Uniform subsampling beyond the point cap keeps the cost per frame bounded.
  const std::size_t n = undistorted.size();
  const std::size_t cap = static_cast<std::size_t>(cfg_.lio.max_points);
  const double stride = n > cap ? double(n) / double(cap) : 1.0;
  std::vector<BodyPoint> pts;
  pts.reserve(std::min(n, cap));
  const Mat3 R_il = cfg_.T_imu_lidar.linear();
  const Pose T_lidar_imu = cfg_.T_imu_lidar.inverse();
  for (double f = 0; f < double(n); f += stride) {
    const LidarPoint& lp = undistorted[static_cast<std::size_t>(f)];
    BodyPoint bp;
    bp.p_imu = lp.p_lidar.cast<double>();
    // Range/bearing covariance in the LiDAR frame, rotated into the IMU frame.
    const Mat3 cov_l = pointCovarianceBody(T_lidar_imu * bp.p_imu, cfg_.lio.range_noise_m, cfg_.lio.beam_noise_deg);
    bp.cov_imu = R_il * cov_l * R_il.transpose();
    pts.push_back(bp);
  }
  return pts;
}

std::vector<PointWithCov> LioOdometry::worldPoints(const std::vector<BodyPoint>& pts) const {
  std::vector<PointWithCov> world;
  world.reserve(pts.size());
  for (const auto& bp : pts) {
    PointWithCov pw;
    pw.p_world = x_.R_world_imu * bp.p_imu + x_.p_world_imu;
    pw.cov_world = worldPointCovariance(x_, P_, bp);
    world.push_back(pw);
  }
  return world;
}

bool LioOdometry::predict(const Frame& frame, LioFrameResult& r) {
  r = LioFrameResult{};
  r.utime = frame.utime;
  r.n_raw_points = static_cast<int>(frame.sweep.points.size());
  watch_.restart();

  // 1. Static initialisation from the first IMU samples (gravity, gyro bias, g units).
  if (!init_.done()) {
    for (const auto& s : frame.imu) {
      if (s.utime <= last_imu_fed_) continue;
      last_imu_fed_ = s.utime;
      if (init_.add(s)) break;
    }
    if (!init_.done()) return false;
    x_ = init_.initialState();
    P_ = initialCovariance();
    propagator_ = std::make_unique<ImuPropagator>(cfg_.imu, init_.accelScale());
    init_message_ = init_.describe();
  }
  r.initialized = true;
  if (frame.utime <= x_.utime) {  // a frame inside the initialisation window: nothing to estimate yet
    r.state = x_;
    r.P = P_;
    return false;
  }

  // 2. Forward propagation to the frame time, keeping the per-sample trace.
  std::vector<ImuTracePoint> trace;
  propagator_->propagate(x_, P_, frame.imu, frame.utime, &trace);

  // 3. Undistort + downsample the sweep, with per-point covariances.
  r.points = preparePoints(frame.sweep, trace);
  r.n_points = static_cast<int>(r.points.size());
  r.state = x_;  // the prediction until update()
  r.P = P_;
  return true;
}

void LioOdometry::update(LioFrameResult& r, const PlaneFinder& planes) {
  // 4. Iterated point-to-plane update against the map (skipped until the map has content).
  if (map_started_ && !r.points.empty()) {
    NavState x = x_;
    StateCov P = P_;
    const LioUpdateResult u = lidarUpdate(x, P, r.points, planes, cfg_.lio);
    r.n_matched = u.matched;
    r.iterations = u.iterations;
    r.rms_residual_m = u.rms_residual_m;
    r.sigma_min = degeneracySigmaMin(u.matched_normals);
    r.matched_index = u.matched_index;
    r.matched_normals = u.matched_normals;
    if (u.matched >= cfg_.min_matches) {
      x_ = x;
      P_ = P;
      r.lio_ok = true;
    }
  }
  r.lio_ms = watch_.elapsedMs();
  r.state = x_;
  r.P = P_;
}

void LioOdometry::markInserted(LioFrameResult& r) {
  if (r.points.empty()) return;
  r.map_started = !map_started_;
  map_started_ = true;
}

LioFrameResult LioOdometry::process(const Frame& frame) {
  LioFrameResult r;
  if (!predict(frame, r)) return r;
  if (map_ == nullptr) throw std::logic_error("LioOdometry::process: no map (remote mode: use predict/update)");
  update(r, map_->lidar().voxels());
  // 5. Map insertion with the posterior pose. As in the reference, the map grows every frame (a failed
  // update keeps the IMU prediction).
  Stopwatch map_watch;
  if (!r.points.empty()) {
    map_->lidar().insert(worldPoints(r.points));
    markInserted(r);
  }
  r.map_ms = map_watch.elapsedMs();
  return r;
}

}  // namespace livo
