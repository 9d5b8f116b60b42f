// The simulator: a scenario's world, trajectory and sensors, producing IMU samples, LiDAR scans and
// camera images in time order, with ground truth. No middleware: processes/livo-sim writes the log.
//
// Sensor times (utime, µs) start at scenario.start_time_s: IMU sample k at start + k / imu.rate_hz,
// LiDAR scan j at start + j / lidar.rate_hz (points carry their own offsets), image k at
// start + camera.phase_s + k / camera.rate_hz. Events are ordered by utime (ties: IMU, LiDAR, camera)
// and cover [start, start + duration_s). Noise comes from counter-based hashes of (seed, stream,
// index), so the output is the same for a seed whatever the number of render threads.
#pragma once

#include "livo/common/types.hpp"
#include "livo/sim/camera_model.hpp"
#include "livo/sim/lidar_pattern.hpp"
#include "livo/sim/scenario.hpp"
#include "livo/sim/trajectory.hpp"
#include "livo/sim/world.hpp"

#include <functional>
#include <iosfwd>
#include <memory>

namespace livo::sim {

constexpr double kGravity = 9.81;  ///< m/s^2, along -z of the world
/// Pixel value = kGrayPerRadiance * gain * radiance + noise, clamped to 0..255 and rounded.
constexpr double kGrayPerRadiance = 230.0;

struct SimOptions {
  int threads = 2;  ///< camera rows and LiDAR rays computed in parallel (output does not depend on it)
};

/// Truth behind one IMU sample.
struct ImuTruth {
  Pose T_world_imu = Pose::Identity();
  Vec3 v_world = Vec3::Zero();
  Vec3 gyro = Vec3::Zero();   ///< exact body rate, rad/s
  Vec3 accel = Vec3::Zero();  ///< exact specific force R^T (a - g), m/s^2
  Vec3 gyro_bias = Vec3::Zero();
  Vec3 accel_bias = Vec3::Zero();
};

/// Truth behind one image.
struct ImageTruth {
  Pose T_world_camera = Pose::Identity();  ///< at mid-exposure
  double gain = 1.0;  ///< exposure gain applied to the radiance (jitter x exposure steps)
  Utime capture_utime = 0;  ///< true mid-exposure time (the image is stamped camera.stamp_delay_s later)
  int blur_samples = 1;     ///< poses averaged over the exposure (1: no motion blur)
};

/// Counters of the LiDAR model.
struct LidarStats {
  std::uint64_t scans = 0, rays = 0, points = 0;
  std::uint64_t no_return = 0;  ///< nothing within max range
  std::uint64_t blind = 0;      ///< closer than blind_m
  std::uint64_t grazing = 0;    ///< incidence beyond max_incidence_deg
};

struct SimEvent {
  enum class Kind { Imu, Lidar, Image } kind = Kind::Imu;
  Utime utime = 0;
  ImuSample imu;
  ImuTruth imu_truth;
  LidarScan scan;
  Image image;
  ImageTruth image_truth;
};

struct SimCallbacks {
  std::function<void(const ImuSample&, const ImuTruth&)> imu;
  std::function<void(const LidarScan&)> lidar;
  std::function<void(const Image&, const ImageTruth&)> image;
};

class Simulator {
 public:
  /// Builds world and trajectory; throws ConfigError / std::runtime_error on bad scenarios.
  explicit Simulator(SimScenario scenario, SimOptions options = {});

  /// Produces the next event in time order; false when the duration is over.
  bool next(SimEvent& ev);
  /// Runs to the end through callbacks (absent callbacks skip the work, e.g. no rendering).
  void run(const SimCallbacks& cb);

  // ---- single sensors (pure functions of the index; used by next() and by tests) ----
  /// LiDAR scan j (starts at lidarUtime(j)); `stats` accumulates counters when given.
  LidarScan lidarScan(std::int64_t j, LidarStats* stats = nullptr) const;
  /// Image k, captured (mid-exposure) at cameraUtime(k) and stamped at cameraStamp(k); requires a
  /// camera. With camera.exposure_time_s the radiance is averaged over poses spread across the
  /// exposure (blurSamples), then exposure gain (jitter, camera.exposure_steps), vignetting and pixel
  /// noise are applied.
  Image renderImage(std::int64_t k, ImageTruth* truth = nullptr) const;
  /// Poses averaged for image k: the rig's motion over the exposure, rotation and translation seen at
  /// 1 m, in pixels at the larger focal length, rounded up (at most a pixel between sub-samples; 1 when
  /// it moves less than a pixel), at most 64.
  int blurSamples(std::int64_t k) const;
  /// Exact (noise-free) IMU measurement at time t (seconds since start).
  void exactImu(double t, Vec3& gyro, Vec3& accel) const;

  Utime imuUtime(std::int64_t k) const;
  Utime lidarUtime(std::int64_t j) const;
  Utime cameraUtime(std::int64_t k) const;
  /// The stamp image k carries: cameraUtime(k) + camera.stamp_delay_s.
  Utime cameraStamp(std::int64_t k) const;
  Utime startUtime() const { return start_; }
  Utime endUtime() const { return end_; }  ///< exclusive
  /// Seconds since the start for a sensor time.
  double relTime(Utime t) const { return static_cast<double>(t - start_) * 1e-6; }

  // ---- ground truth ----
  Pose T_world_imu(Utime t) const { return traj_.pose(relTime(t)); }
  Pose T_world_lidar(Utime t) const { return T_world_imu(t) * sc_.extrinsics.T_imu_lidar; }
  Pose T_world_camera(Utime t) const { return T_world_imu(t) * sc_.extrinsics.T_imu_camera; }
  BodyState bodyState(Utime t) const { return traj_.state(relTime(t)); }

  const SimScenario& scenario() const { return sc_; }
  const World& world() const { return world_; }
  const SimTrajectory& trajectory() const { return traj_; }
  const LidarPattern& lidarPattern() const { return pattern_; }
  bool hasCamera() const { return static_cast<bool>(camera_); }
  const SimCameraModel& camera() const { return *camera_; }
  const LidarStats& lidarStats() const { return stats_; }

  /// Rig config for livo-run (config/README.md schema: environment, imu, lidar, camera, selector).
  void writeRigConfig(std::ostream& out) const;

 private:
  void addVibration(double t_rel, ImuSample& s) const;
  /// Adds weight x the radiance seen from camera pose T_wc to acc (one value per pixel).
  void accumulateRadiance(const Pose& T_wc, double weight, std::vector<double>& acc) const;
  void imuSample(std::int64_t k, ImuSample& s, ImuTruth& truth);
  /// Rays [first, last) of scan j (which starts t0 s after the start): returns into `points`, the
  /// rays without one counted in `st`.
  void traceRays(std::int64_t j, double t0, const std::vector<LidarRay>& rays, std::size_t first, std::size_t last,
                 std::vector<LidarPoint>& points, LidarStats& st) const;

  SimScenario sc_;
  SimOptions opt_;
  SimTrajectory traj_;
  World world_;
  LidarPattern pattern_;
  std::unique_ptr<SimCameraModel> camera_;
  Utime start_ = 0, end_ = 0;
  std::uint64_t seed_ = 0;

  // Event cursors and the IMU bias random walk state.
  std::int64_t next_imu_ = 0, next_scan_ = 0, next_image_ = 0;
  Vec3 gyro_bias_ = Vec3::Zero(), accel_bias_ = Vec3::Zero();
  LidarStats stats_;
};

/// Writes the rig config of a scenario (same as Simulator::writeRigConfig).
void writeRigConfig(const SimScenario& scenario, std::ostream& out);

}  // namespace livo::sim
