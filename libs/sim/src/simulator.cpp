#include "livo/sim/simulator.hpp"

#include "parallel.hpp"
#include "livo/sim/random.hpp"
#include "livo/sim/world_gen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace livo::sim {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kCameraMaxRange = 2000.0;  // metres; beyond: sky

// Direction of ray i of scan j after beam noise: `dir` tilted by two normal deviates of `sigma` rad.
Vec3 perturbedBeam(const Vec3& dir, double sigma, std::uint64_t seed, std::uint64_t j, std::size_t i) {
  const Vec3 e1 = dir.unitOrthogonal(), e2 = dir.cross(e1);
  double n1, n2;
  gaussianPairFromKeys(seed, RngStream::LidarBeam, j, i, n1, n2);
  return (dir + sigma * (n1 * e1 + n2 * e2)).normalized();
}

void addLidarStats(LidarStats& sum, const LidarStats& s) {
  sum.scans += s.scans;
  sum.rays += s.rays;
  sum.points += s.points;
  sum.no_return += s.no_return;
  sum.blind += s.blind;
  sum.grazing += s.grazing;
}
/// The path the world is laid out along. With world.seed set (one world for several runs), the path as
/// if it started at its nominal start, so that trajectory.start_m moves the robot, not the buildings;
/// without, the trajectory's own path (the worlds of every scenario as before).
std::vector<Vec3> worldPath(const SimScenario& sc, const std::vector<Vec3>& trajectory_path) {
  if (sc.world.seed < 0 || sc.trajectory.start_m == 0.0) return trajectory_path;
  TrajectoryConfig nominal = sc.trajectory;
  nominal.start_m = 0.0;
  return makePathPolyline(nominal, sc.world);
}

}  // namespace

Simulator::Simulator(SimScenario scenario, SimOptions options)
    : sc_(std::move(scenario)),
      opt_(options),
      traj_((sc_.validate(), sc_.trajectory), sc_.world),
      world_(makeWorld(sc_, worldPath(sc_, traj_.path()))),
      pattern_(sc_.lidar) {
  if (sc_.camera.enabled) camera_ = std::make_unique<SimCameraModel>(sc_.camera);
  start_ = sc_.startUtime();
  end_ = start_ + fromSeconds(sc_.duration_s);
  seed_ = static_cast<std::uint64_t>(sc_.seed);
  gyro_bias_ = sc_.imu.gyro_bias_init;
  accel_bias_ = sc_.imu.accel_bias_init;
}

Utime Simulator::imuUtime(std::int64_t k) const {
  return start_ + static_cast<Utime>(std::llround(static_cast<double>(k) * 1e6 / sc_.imu.rate_hz));
}
Utime Simulator::lidarUtime(std::int64_t j) const {
  return start_ + static_cast<Utime>(std::llround(static_cast<double>(j) * 1e6 / sc_.lidar.rate_hz));
}
Utime Simulator::cameraUtime(std::int64_t k) const {
  return start_ + static_cast<Utime>(std::llround((sc_.camera.phase_s + static_cast<double>(k) / sc_.camera.rate_hz) * 1e6));
}
Utime Simulator::cameraStamp(std::int64_t k) const { return cameraUtime(k) + fromSeconds(sc_.camera.stamp_delay_s); }

void Simulator::exactImu(double t, Vec3& gyro, Vec3& accel) const {
  const BodyState s = traj_.state(t);
  gyro = s.omega_body;
  // Specific force: f = R^T (a - g), g = (0, 0, -9.81).
  accel = s.T_world_imu.linear().transpose() * (s.a_world + Vec3(0.0, 0.0, kGravity));
}

// IMU model (Kalibr convention): discrete white noise sigma_d = sigma_c sqrt(rate); the bias is a
// random walk b_{k+1} = b_k + sigma_bw sqrt(dt) n_k.
void Simulator::imuSample(std::int64_t k, ImuSample& s, ImuTruth& truth) {
  const auto& c = sc_.imu;
  s.utime = imuUtime(k);
  const double t = relTime(s.utime);
  const BodyState b = traj_.state(t);
  truth.T_world_imu = b.T_world_imu;
  truth.v_world = b.v_world;
  exactImu(t, truth.gyro, truth.accel);
  truth.gyro_bias = gyro_bias_;
  truth.accel_bias = accel_bias_;
  const double sg = c.gyro_noise * std::sqrt(c.rate_hz), sa = c.accel_noise * std::sqrt(c.rate_hz);
  const auto kk = static_cast<std::uint64_t>(k);
  for (int a = 0; a < 3; ++a) {
    s.gyro[a] = truth.gyro[a] + gyro_bias_[a] + sg * gaussianFromKeys(seed_, RngStream::ImuGyroNoise, kk, a);
    s.accel[a] = truth.accel[a] + accel_bias_[a] + sa * gaussianFromKeys(seed_, RngStream::ImuAccelNoise, kk, a);
  }
  if (c.vibration.active()) addVibration(t, s);
  if (SimScenario::inDropout(c.fault_s, t)) {  // the IMU fault: a bias jump while it lasts
    s.accel += c.fault_accel_mps2;
    truth.accel_bias += c.fault_accel_mps2;
  }
  const double sq_dt = std::sqrt(1.0 / c.rate_hz);
  for (int a = 0; a < 3; ++a) {
    gyro_bias_[a] += c.gyro_bias_walk * sq_dt * gaussianFromKeys(seed_, RngStream::ImuGyroWalk, kk, a);
    accel_bias_[a] += c.accel_bias_walk * sq_dt * gaussianFromKeys(seed_, RngStream::ImuAccelWalk, kk, a);
  }
}

// Four tones within +-10 % of the frequency per axis and sensor, seeded phases, RMS = the amplitude:
// a sinusoid plus band-limited noise around it (half of the power in the centre tone).
void Simulator::addVibration(double t, ImuSample& s) const {
  const VibrationConfig& v = sc_.imu.vibration;
  static constexpr double kOffsets[4] = {0.0, -0.07, 0.04, 0.1};
  static constexpr double kPower[4] = {0.5, 0.2, 0.15, 0.15};
  for (int a = 0; a < 3; ++a) {
    double g = 0.0, acc = 0.0;
    for (int k = 0; k < 4; ++k) {
      const double f = v.freq_hz * (1.0 + kOffsets[k]);
      const double amp = std::sqrt(2.0 * kPower[k]);  // RMS of amp * sin = sqrt(power)
      const double pg = 2.0 * M_PI * uniformFromHash(hashKeys(seed_, std::uint64_t(RngStream::ImuVibration), std::uint64_t(k), std::uint64_t(a)));
      const double pa = 2.0 * M_PI * uniformFromHash(hashKeys(seed_, std::uint64_t(RngStream::ImuVibration), std::uint64_t(k + 8), std::uint64_t(a)));
      g += amp * std::sin(2.0 * M_PI * f * t + pg);
      acc += amp * std::sin(2.0 * M_PI * f * t + pa);
    }
    s.gyro[a] += v.gyro_rad_s * g;
    s.accel[a] += v.accel_mps2 * acc;
  }
}

LidarScan Simulator::lidarScan(std::int64_t j, LidarStats* stats) const {
  const std::vector<double>& freeze = sc_.lidar.freeze_s;
  for (std::size_t i = 0; i + 1 < freeze.size(); i += 2) {  // a frozen LiDAR repeats its last scan
    const double t = relTime(lidarUtime(j));
    if (!(t >= freeze[i] && t < freeze[i + 1])) continue;
    std::int64_t last = j;
    while (last > 0 && relTime(lidarUtime(last)) >= freeze[i]) --last;
    if (relTime(lidarUtime(last)) >= freeze[i]) break;  // nothing before the freeze to repeat
    LidarScan scan = lidarScan(last, stats);
    scan.utime = lidarUtime(j);
    return scan;
  }
  LidarScan scan;
  scan.utime = lidarUtime(j);
  scan.sensor = sc_.lidar.model;
  std::vector<LidarRay> rays;
  const double t0 = relTime(scan.utime);
  pattern_.rays(t0, rays);

  // Contiguous parts of the ray list per thread; each fills its own point list and counters.
  const int threads = std::clamp(opt_.threads, 1, 16);
  std::vector<std::vector<LidarPoint>> parts(static_cast<std::size_t>(threads));
  std::vector<LidarStats> part_stats(static_cast<std::size_t>(threads));
  runParts(threads, [&](int part, int n_parts) {
    const std::size_t first = rays.size() * part / n_parts, last = rays.size() * (part + 1) / n_parts;
    traceRays(j, t0, rays, first, last, parts[static_cast<std::size_t>(part)],
              part_stats[static_cast<std::size_t>(part)]);
  });

  // The parts in ray order, so that the scan does not depend on the number of threads.
  LidarStats local;
  local.scans = 1;
  local.rays = rays.size();
  std::size_t total = 0;
  for (const auto& p : parts) total += p.size();
  scan.points.reserve(total);
  for (std::size_t k = 0; k < parts.size(); ++k) {
    scan.points.insert(scan.points.end(), parts[k].begin(), parts[k].end());
    addLidarStats(local, part_stats[k]);
  }
  local.points = scan.points.size();
  if (stats) addLidarStats(*stats, local);
  return scan;
}

void Simulator::traceRays(std::int64_t j, double t0, const std::vector<LidarRay>& rays, std::size_t first,
                          std::size_t last, std::vector<LidarPoint>& points, LidarStats& st) const {
  const auto& c = sc_.lidar;
  const double cos_max = std::cos(c.max_incidence_deg * kPi / 180.0);
  const double beam_sigma = c.beam_noise_deg * kPi / 180.0;
  const auto jj = static_cast<std::uint64_t>(j);
  points.reserve(last - first);
  Pose T_world_lidar = Pose::Identity();
  float pose_offset = -1.f;
  for (std::size_t i = first; i < last; ++i) {
    const LidarRay& r = rays[i];
    if (r.time_offset_s != pose_offset) {  // rays of one firing share the pose of their time
      pose_offset = r.time_offset_s;
      T_world_lidar = traj_.pose(t0 + static_cast<double>(r.time_offset_s)) * sc_.extrinsics.T_imu_lidar;
    }
    // The beam leaves along a slightly perturbed direction (beam noise) but the sensor reports the
    // range along its nominal direction.
    const Vec3 beam = beam_sigma > 0.0 ? perturbedBeam(r.dir, beam_sigma, seed_, jj, i) : r.dir;
    const Vec3 dir_world = T_world_lidar.linear() * beam;
    const Hit hit = world_.raycast(T_world_lidar.translation(), dir_world, c.max_range_m, c.beam_divergence_mrad * 1e-3);
    if (!hit.valid) {
      ++st.no_return;
      continue;
    }
    if (hit.cosIncidence(dir_world) < cos_max) {
      ++st.grazing;
      continue;
    }
    const double range = hit.distance + c.range_noise_m * gaussianFromKeys(seed_, RngStream::LidarRange, jj, i);
    if (range < c.blind_m) {
      ++st.blind;
      continue;
    }
    if (range > c.max_range_m) {
      ++st.no_return;
      continue;
    }
    LidarPoint p;
    p.p_lidar = (range * r.dir).cast<float>();
    p.time_offset_s = r.time_offset_s;
    p.intensity = static_cast<float>(255.0 * hit.albedo);
    p.ring = r.ring;
    points.push_back(p);
  }
}

int Simulator::blurSamples(std::int64_t k) const {
  const double T = sc_.camera.exposure_time_s;
  if (!(T > 0.0)) return 1;
  const double t = relTime(cameraUtime(k));
  const Pose a = T_world_camera(start_ + fromSeconds(t - 0.5 * T)), b = T_world_camera(start_ + fromSeconds(t + 0.5 * T));
  const double angle = Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
  const double metres = (b.translation() - a.translation()).norm();  // seen at 1 m
  const double px = (angle + metres) * std::max(sc_.camera.fx, sc_.camera.fy);
  return static_cast<int>(std::clamp(std::ceil(px), 1.0, 64.0));  // at most a pixel between samples
}

void Simulator::accumulateRadiance(const Pose& T_wc, double weight, std::vector<double>& acc) const {
  const SimCameraModel& cam = *camera_;
  const Mat3 R = T_wc.linear();
  const Vec3 origin = T_wc.translation();
  // Tiles of kTile x kTile pixels: the primitives inside the cone of a tile's rays are few, so the
  // tile's rays test those (with a bounds pre-test) instead of walking the BVH; crowded tiles use the
  // BVH. Both give the same hit.
  constexpr int kTile = 16;
  constexpr std::size_t kMaxCandidates = 24;
  const int w = cam.width(), h = cam.height();
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  const std::size_t width = static_cast<std::size_t>(w);
  auto renderTiles = [&](int first, int step) {  // tile rows first, first + step, ...
    std::vector<int> candidates;
    std::vector<Vec3> dirs(kTile * kTile);
    for (int ty = first; ty < tiles_y; ty += step)
      for (int tx = 0; tx < tiles_x; ++tx) {
        const int r0 = ty * kTile, r1 = std::min(r0 + kTile, h);
        const int c0 = tx * kTile, c1 = std::min(c0 + kTile, w);
        Vec3 sum = Vec3::Zero();
        for (int r = r0; r < r1; ++r)
          for (int c = c0; c < c1; ++c) {
            const std::size_t i = static_cast<std::size_t>(r) * width + static_cast<std::size_t>(c);
            Vec3& d = dirs[static_cast<std::size_t>((r - r0) * kTile + (c - c0))];
            d = R * cam.rays()[i].cast<double>();
            if (cam.valid()[i]) sum += d;
          }
        if (sum.squaredNorm() == 0.0) continue;  // no valid pixel
        const Vec3 axis = sum.normalized();
        double cos_min = 1.0;
        for (int r = r0; r < r1; ++r)
          for (int c = c0; c < c1; ++c)
            if (cam.valid()[static_cast<std::size_t>(r) * width + static_cast<std::size_t>(c)])
              cos_min = std::min(cos_min, axis.dot(dirs[static_cast<std::size_t>((r - r0) * kTile + (c - c0))]));
        world_.primitivesInCone(origin, axis, std::acos(std::clamp(cos_min, -1.0, 1.0)) + 1e-6, kCameraMaxRange, candidates);
        const bool use_bvh = candidates.size() > kMaxCandidates;
        for (int r = r0; r < r1; ++r)
          for (int c = c0; c < c1; ++c) {
            const std::size_t i = static_cast<std::size_t>(r) * width + static_cast<std::size_t>(c);
            if (!cam.valid()[i]) continue;
            const Vec3& dir = dirs[static_cast<std::size_t>((r - r0) * kTile + (c - c0))];
            const Hit hit = use_bvh ? world_.raycast(origin, dir, kCameraMaxRange, cam.pixelAngle()[i])
                                    : world_.raycastAmong(candidates, origin, dir, kCameraMaxRange, cam.pixelAngle()[i]);
            acc[i] += weight * (hit.valid ? world_.radiance(hit) : World::skyRadiance(dir));
          }
      }
  };
  runParts(std::clamp(opt_.threads, 1, 16), renderTiles);
}

Image Simulator::renderImage(std::int64_t k, ImageTruth* truth) const {
  const SimCameraModel& cam = *camera_;
  const CameraSimConfig& cc = sc_.camera;
  Image img;
  const Utime t_capture = cameraUtime(k);
  img.utime = cameraStamp(k);
  img.width = cam.width();
  img.height = cam.height();
  img.row_stride = img.width;
  img.format = PixelFormat::Gray8;
  img.exposure_time_s = 0.f;  // unknown: the estimator estimates the exposure
  img.data.assign(static_cast<std::size_t>(img.width) * img.height, 0);
  const Pose T_wc = T_world_camera(t_capture);
  // Exposure gain: a per-frame log-normal jitter times the auto-exposure steps passed by then.
  double gain = std::exp(cc.exposure_jitter * gaussianFromKeys(seed_, RngStream::CameraExposure, static_cast<std::uint64_t>(k)));
  const double t_rel = relTime(t_capture);
  for (std::size_t i = 0; i + 1 < cc.exposure_steps.size(); i += 2)
    if (t_rel >= cc.exposure_steps[i]) gain *= cc.exposure_steps[i + 1];
  // Motion blur: the radiance averaged over poses at the centres of n equal parts of the exposure
  // (n = 1: the pose at the capture time, weight 1).
  const int n = blurSamples(k);
  if (truth) {
    truth->T_world_camera = T_wc;
    truth->gain = gain;
    truth->capture_utime = t_capture;
    truth->blur_samples = n;
  }
  const std::size_t width = static_cast<std::size_t>(img.width);
  std::vector<double> radiance(width * static_cast<std::size_t>(img.height), 0.0);
  for (int s = 0; s < n; ++s) {
    const double dt = cc.exposure_time_s * ((s + 0.5) / n - 0.5);
    accumulateRadiance(T_world_camera(t_capture + fromSeconds(dt)), 1.0 / n, radiance);
  }
  // Vignetting 1 - k r^2, r the distance from the principal point over that of the farthest corner.
  double r2_corner = 0.0;
  for (double u : {0.0, double(img.width - 1)})
    for (double v : {0.0, double(img.height - 1)})
      r2_corner = std::max(r2_corner, (u - cc.cx) * (u - cc.cx) + (v - cc.cy) * (v - cc.cy));
  const double kv = cc.vignetting / std::max(r2_corner, 1e-12);
  // Pixel noise: one Box-Muller pair per two horizontally adjacent pixels (keys: frame, row, pair).
  const double sigma = cc.pixel_noise;
  auto expose = [&](int first, int step) {
    for (int r = first; r < img.height; r += step)
      for (int c = 0; c < img.width; c += 2) {
        double noise[2] = {0.0, 0.0};
        if (sigma > 0.0)
          gaussianPairFromKeys(seed_, RngStream::CameraPixel, static_cast<std::uint64_t>(k),
                               (static_cast<std::uint64_t>(r) << 32) | static_cast<std::uint64_t>(c / 2), noise[0], noise[1]);
        for (int hh = 0; hh < 2 && c + hh < img.width; ++hh) {
          const std::size_t i = static_cast<std::size_t>(r) * width + static_cast<std::size_t>(c + hh);
          if (!cam.valid()[i]) continue;
          double rad = radiance[i];
          if (kv > 0.0) {
            const double du = c + hh - cc.cx, dv = r - cc.cy;
            rad *= 1.0 - kv * (du * du + dv * dv);
          }
          const double value = kGrayPerRadiance * gain * rad + sigma * noise[hh];
          img.data[i] = static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
        }
      }
  };
  runParts(std::clamp(opt_.threads, 1, 16), expose);
  return img;
}

bool Simulator::next(SimEvent& ev) {
  for (;;) {
    const Utime t_imu = imuUtime(next_imu_);
    const Utime t_scan = lidarUtime(next_scan_);
    const Utime t_cam = camera_ ? cameraStamp(next_image_) : std::numeric_limits<Utime>::max();
    const Utime t = std::min({t_imu, t_scan, t_cam});
    if (t >= end_) return false;
    ev.utime = t;
    if (t == t_imu) {
      ev.kind = SimEvent::Kind::Imu;
      imuSample(next_imu_++, ev.imu, ev.imu_truth);
      return true;
    }
    if (t == t_scan) {
      const std::int64_t j = next_scan_++;
      if (SimScenario::inDropout(sc_.lidar.dropouts_s, relTime(t))) continue;  // a dropped scan
      ev.kind = SimEvent::Kind::Lidar;
      ev.scan = lidarScan(j, &stats_);
      return true;
    }
    const std::int64_t k = next_image_++;
    if (SimScenario::inDropout(sc_.camera.dropouts_s, relTime(t))) continue;  // a dropped image
    ev.kind = SimEvent::Kind::Image;
    ev.image = renderImage(k, &ev.image_truth);
    return true;
  }
}

void Simulator::run(const SimCallbacks& cb) {
  for (;;) {
    const Utime t_imu = imuUtime(next_imu_);
    const Utime t_scan = lidarUtime(next_scan_);
    const Utime t_cam = camera_ ? cameraStamp(next_image_) : std::numeric_limits<Utime>::max();
    const Utime t = std::min({t_imu, t_scan, t_cam});
    if (t >= end_) return;
    if (t == t_imu) {
      ImuSample s;
      ImuTruth truth;
      imuSample(next_imu_++, s, truth);  // always: the bias walk is sequential
      if (cb.imu) cb.imu(s, truth);
    } else if (t == t_scan) {
      if (cb.lidar && !SimScenario::inDropout(sc_.lidar.dropouts_s, relTime(t))) cb.lidar(lidarScan(next_scan_, &stats_));
      ++next_scan_;
    } else {
      if (cb.image && !SimScenario::inDropout(sc_.camera.dropouts_s, relTime(t))) {
        ImageTruth truth;
        const Image img = renderImage(next_image_, &truth);
        cb.image(img, truth);
      }
      ++next_image_;
    }
  }
}

void Simulator::writeRigConfig(std::ostream& out) const { sim::writeRigConfig(sc_, out); }

}  // namespace livo::sim
