// Simulator scenario: the plain config structs read from config/sim/*.yaml.
//
// The simulator's scenario keys (the contract: docs/contract-changes.md lists what changed) plus optional
// extras, all documented in config/sim/README.md. Defaults and units live in the declarations; `load()` only overrides what the
// file names, and loadScenarioFile() rejects keys that nothing reads.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/types.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace livo::sim {

struct WorldConfig {
  std::string kind = "room";  ///< room | corridor | street | wall
  /// room: box [x, y, z]; corridor: [length, width, height]; street: road loop [x, y] + max building
  /// height z; wall: [distance in front of the start, width, height]. Metres.
  Eigen::Vector3d size_m{10.0, 8.0, 3.0};
  std::string texture = "noise";  ///< noise | images | none
  std::vector<std::string> texture_images;  ///< photos for texture: images (paths relative to the file)
  double texture_tile_m = 2.0;     ///< images: metres covered by one photo's width
  double texture_scale_m = 1.0;    ///< noise: wavelength of the coarsest octave, metres
  double clutter = 0.5;            ///< 0..1: density of furniture / street furniture
  /// street: the layout of the first repeat_m metres of road repeats along the rest (identical blocks,
  /// the place-recognition trap); 0: none
  double repeat_m = 0.0;
  /// Seed of the world's layout and texture, apart from the sensor noise: two scenarios with one
  /// world.seed and different `seed`s drive through the same world with other noise. -1: the scenario's seed.
  std::int64_t seed = -1;
  void load(const ConfigNode& n);
};

struct TrajectoryConfig {
  std::string kind = "loop";  ///< loop | lissajous | waypoints
  double speed_mps = 1.0;     ///< cruise speed limit
  double max_rot_dps = 60.0;  ///< body angular rate limit (path turns + sway)
  double max_accel_mps2 = 1.5;  ///< limit of the speed profile's tangential acceleration
  double static_s = 2.0;      ///< at rest at the start (static initialisation)
  double ramp_s = 2.0;        ///< C2 ramp from rest to cruise
  /// Path extents [x, y, z]: loop = rounded rectangle x by y with vertical wave z (peak to peak);
  /// lissajous = peak-to-peak amplitudes. Zero: chosen from the world.
  Eigen::Vector3d size_m{0.0, 0.0, 0.0};
  Eigen::Vector3d center_m{0.0, 0.0, 0.0};  ///< path centre; z = 0 means "height_m"
  double height_m = 0.0;           ///< carrying height above the floor (0: 1.4 indoor, 1.8 street)
  double corner_radius_m = 0.0;    ///< loop corner radius (0: half the smaller side, an oval)
  double start_m = 0.0;            ///< where on the closed path the motion starts (arc length, metres)
  Eigen::Vector3d frequencies{3.0, 2.0, 5.0};  ///< lissajous: integer frequency ratios x, y, z
  std::vector<double> waypoints;   ///< waypoints: x, y, z triples of a closed path (>= 3 points)
  std::vector<double> look_at;     ///< [x, y, z]: yaw faces this point instead of the travel direction
  /// What carries the rig: handheld | car | drone; empty: car on a street, handheld elsewhere. It sets
  /// the defaults of sway_deg and bob_m (motionOf / swayDegOf / bobMOf).
  std::string motion;
  std::optional<double> sway_deg;  ///< roll / pitch / yaw sway amplitude; unset: handheld 2 deg, car and drone 0
  std::optional<double> bob_m;     ///< vertical step bob amplitude; unset: handheld 0.02 m, car and drone 0
  double pitch_deg = 0.0;          ///< constant pitch (positive: nose down)
  void load(const ConfigNode& n);
  /// The motion kind with its default applied (car on a street, handheld elsewhere).
  std::string motionIn(const WorldConfig& world) const;
  /// sway_deg and bob_m with the motion's defaults applied.
  double swayDegIn(const WorldConfig& world) const;
  double bobMIn(const WorldConfig& world) const;
  static constexpr double kHandheldSwayDeg = 2.0;
  static constexpr double kHandheldBobM = 0.02;
};

struct LidarSimConfig {
  std::string model = "avia";  ///< avia | mid360 | spinning32
  double rate_hz = 10.0;
  double range_noise_m = 0.01;   ///< Gaussian sigma on the range
  double beam_noise_deg = 0.0;   ///< Gaussian sigma of the beam direction (point reported on the nominal one)
  double max_range_m = 60.0;
  double blind_m = 0.5;          ///< no return closer than this
  double max_incidence_deg = 80.0;  ///< no return when the beam meets the surface more obliquely
  double points_per_second = 0.0;   ///< 0: model default (avia 240k, mid360 200k, spinning32 327680)
  double beam_divergence_mrad = 3.0;  ///< footprint for the intensity lookup
  /// [t0, t1, t0, t1, ...] seconds from the start: no scan starts inside any [t0, t1) (a blinded or
  /// dropped LiDAR stream).
  std::vector<double> dropouts_s;
  /// [t0, t1, ...] seconds from the start: a frozen LiDAR (off by default): every scan that starts
  /// inside [t0, t1) repeats the points of the last scan before t0 (same returns, the new stamp).
  std::vector<double> freeze_s;
  void load(const ConfigNode& n);
};

/// Rotor-like vibration added to the IMU measurements only (the rig's motion is unchanged): per axis
/// a sinusoid at freq_hz plus band-limited noise around it (four tones within +-10 % of freq_hz with
/// seeded phases); accel_mps2 and gyro_rad_s are the RMS amplitudes per axis.
struct VibrationConfig {
  double accel_mps2 = 0.0;
  double gyro_rad_s = 0.0;
  double freq_hz = 100.0;
  void load(const ConfigNode& n);
  bool active() const { return accel_mps2 > 0 || gyro_rad_s > 0; }
};

struct ImuSimConfig {
  double rate_hz = 200.0;
  double gyro_noise = 1.7e-4;       ///< rad/s/sqrt(Hz), continuous-time density
  double accel_noise = 2.0e-3;      ///< m/s^2/sqrt(Hz)
  double gyro_bias_walk = 1.9e-5;   ///< rad/s^2/sqrt(Hz)
  double accel_bias_walk = 3.0e-3;  ///< m/s^3/sqrt(Hz)
  Eigen::Vector3d gyro_bias_init{0.0, 0.0, 0.0};   ///< rad/s
  Eigen::Vector3d accel_bias_init{0.0, 0.0, 0.0};  ///< m/s^2
  VibrationConfig vibration;       ///< imu.vibration {accel_mps2, gyro_rad_s, freq_hz}
  /// An IMU fault (off by default): inside every [t0, t1) of fault_s (seconds from the start) the
  /// accelerometer reads fault_accel_mps2 more (body frame), a bias jump that comes and goes.
  std::vector<double> fault_s;
  Eigen::Vector3d fault_accel_mps2{0.0, 0.0, 0.0};
  void load(const ConfigNode& n);
};

struct CameraSimConfig {
  bool enabled = true;
  std::string model = "pinhole";  ///< pinhole (radtan k1 k2 p1 p2) | equidistant (k1..k4)
  int width = 640;
  int height = 512;
  double fx = 400.0, fy = 400.0, cx = 319.5, cy = 255.5;
  std::vector<double> distortion{0.0, 0.0, 0.0, 0.0};
  double max_angle_deg = 95.0;  ///< equidistant: pixels beyond this angle from the axis are black
  double rate_hz = 10.0;
  double phase_s = 0.037;       ///< first image time after the start (independent of LiDAR scans)
  double exposure_jitter = 0.1;  ///< sigma of log(gain), per frame
  double pixel_noise = 2.0;      ///< Gaussian sigma, gray levels
  std::vector<double> dropouts_s;  ///< [t0, t1, ...] seconds from the start: no image inside any [t0, t1)
  /// Faults of real cameras (config/sim/README.md), all off by default:
  double exposure_time_s = 0.0;  ///< > 0: motion blur, the radiance integrated over the exposure
  std::vector<double> exposure_steps;  ///< [t, factor, ...]: the gain is multiplied by factor from t on
  double vignetting = 0.0;       ///< k of the radial fall-off 1 - k r^2 (r = 1 at the farthest corner)
  double stamp_delay_s = 0.0;    ///< images are stamped this long after their mid-exposure time
  void load(const ConfigNode& n);
};

struct ExtrinsicsConfig {
  Eigen::Isometry3d T_imu_lidar = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_imu_camera = defaultCamera();
  static Eigen::Isometry3d defaultCamera();  ///< forward looking: q = [-0.5, 0.5, -0.5, 0.5]
  void load(const ConfigNode& n);
};

/// The `map` section of the rig config that livo-sim --rig writes, for scenarios scaled down from the
/// map's defaults (a 200 m local cube holds all of a small revisit loop). 0: the key is not written
/// (the map's default applies). Checked again by the map's own config when the rig is loaded.
struct RigMapConfig {
  double local_edge_m = 0.0;
  double slide_distance_m = 0.0;
  double longterm_edge_m = 0.0;
  double longterm_slide_m = 0.0;
  double tile_edge_m = 0.0;
  /// Every key with its field, in the order written (load, validation and the rig writer use it).
  static constexpr std::pair<const char*, double RigMapConfig::*> kKeys[] = {
      {"local_edge_m", &RigMapConfig::local_edge_m},         {"slide_distance_m", &RigMapConfig::slide_distance_m},
      {"longterm_edge_m", &RigMapConfig::longterm_edge_m},   {"longterm_slide_m", &RigMapConfig::longterm_slide_m},
      {"tile_edge_m", &RigMapConfig::tile_edge_m}};
  bool any() const {
    for (const auto& [key, field] : kKeys)
      if (this->*field > 0) return true;
    return false;
  }
  void load(const ConfigNode& n) {
    for (const auto& [key, field] : kKeys) n.get(key, this->*field);
  }
};

/// A complete scenario.
struct SimScenario {
  std::string source = "<scenario>";  ///< file name, for error messages
  std::string base_dir = ".";      ///< folder of the scenario file (relative texture paths)
  std::int64_t seed = 1;
  double duration_s = 20.0;
  double start_time_s = 1.7e9;     ///< epoch of the first sample (exercises large time stamps)
  std::string environment;         ///< indoor | outdoor; empty: street outdoor, others indoor
  WorldConfig world;
  TrajectoryConfig trajectory;
  LidarSimConfig lidar;
  ImuSimConfig imu;
  CameraSimConfig camera;
  ExtrinsicsConfig extrinsics;
  RigMapConfig rig_map;            ///< section `rig_map`: the written rig's `map` section

  void load(const ConfigNode& root);
  /// Throws ConfigError on inconsistent values (naming the key).
  void validate() const;
  Utime startUtime() const { return fromSeconds(start_time_s); }
  /// Whether `t_rel` (seconds from the start) falls in one of the [t0, t1) intervals.
  static bool inDropout(const std::vector<double>& intervals, double t_rel);
  std::string environmentOrDefault() const;
};

/// Loads a scenario file, rejects unknown keys and validates it. Throws ConfigError.
SimScenario loadScenarioFile(const std::string& path);
/// Same from a YAML string (tests); `base_dir` resolves relative texture paths.
SimScenario parseScenario(const std::string& yaml, const std::string& base_dir = ".");

}  // namespace livo::sim
