#include "livo/sim/scenario.hpp"

#include "livo/common/so3.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace livo::sim {

void WorldConfig::load(const ConfigNode& n) {
  n.get("kind", kind).get("size_m", size_m).get("texture", texture).get("texture_images", texture_images);
  n.get("texture_tile_m", texture_tile_m).get("texture_scale_m", texture_scale_m).get("clutter", clutter);
  n.get("repeat_m", repeat_m).get("seed", seed);
}

void TrajectoryConfig::load(const ConfigNode& n) {
  n.get("kind", kind).get("speed_mps", speed_mps).get("max_rot_dps", max_rot_dps);
  n.get("max_accel_mps2", max_accel_mps2).get("static_s", static_s).get("ramp_s", ramp_s);
  n.get("size_m", size_m).get("center_m", center_m).get("height_m", height_m);
  n.get("start_m", start_m).get("corner_radius_m", corner_radius_m).get("frequencies", frequencies).get("waypoints", waypoints);
  n.get("look_at", look_at).get("motion", motion).get("pitch_deg", pitch_deg);
  // Absent: the motion's default (swayDegIn / bobMIn).
  for (auto [key, field] : {std::make_pair("sway_deg", &sway_deg), std::make_pair("bob_m", &bob_m)})
    if (n.has(key)) {
      double v = 0.0;
      n.get(key, v);
      *field = v;
    }
}

std::string TrajectoryConfig::motionIn(const WorldConfig& world) const {
  if (!motion.empty()) return motion;
  return world.kind == "street" ? "car" : "handheld";
}

double TrajectoryConfig::swayDegIn(const WorldConfig& world) const {
  if (sway_deg) return *sway_deg;
  return motionIn(world) == "handheld" ? kHandheldSwayDeg : 0.0;
}

double TrajectoryConfig::bobMIn(const WorldConfig& world) const {
  if (bob_m) return *bob_m;
  return motionIn(world) == "handheld" ? kHandheldBobM : 0.0;
}

void LidarSimConfig::load(const ConfigNode& n) {
  n.get("model", model).get("rate_hz", rate_hz).get("range_noise_m", range_noise_m);
  n.get("max_range_m", max_range_m).get("blind_m", blind_m).get("max_incidence_deg", max_incidence_deg);
  n.get("beam_noise_deg", beam_noise_deg);
  n.get("points_per_second", points_per_second).get("beam_divergence_mrad", beam_divergence_mrad);
  n.get("dropouts_s", dropouts_s).get("freeze_s", freeze_s);
}

void VibrationConfig::load(const ConfigNode& n) {
  n.get("accel_mps2", accel_mps2).get("gyro_rad_s", gyro_rad_s).get("freq_hz", freq_hz);
  n.check(accel_mps2 >= 0 && accel_mps2 < 100, "accel_mps2", "must be in [0, 100) m/s^2 (RMS)");
  n.check(gyro_rad_s >= 0 && gyro_rad_s < 20, "gyro_rad_s", "must be in [0, 20) rad/s (RMS)");
  n.check(freq_hz > 0 && freq_hz < 10000, "freq_hz", "must be in (0, 10000) Hz");
}

bool SimScenario::inDropout(const std::vector<double>& iv, double t) {
  for (std::size_t i = 0; i + 1 < iv.size(); i += 2)
    if (t >= iv[i] && t < iv[i + 1]) return true;
  return false;
}

void ImuSimConfig::load(const ConfigNode& n) {
  n.get("rate_hz", rate_hz).get("gyro_noise", gyro_noise).get("accel_noise", accel_noise);
  n.get("gyro_bias_walk", gyro_bias_walk).get("accel_bias_walk", accel_bias_walk);
  n.get("gyro_bias_init", gyro_bias_init).get("accel_bias_init", accel_bias_init);
  vibration.load(n.section("vibration"));
  n.get("fault_s", fault_s).get("fault_accel_mps2", fault_accel_mps2);
  n.check(fault_accel_mps2.allFinite() && fault_accel_mps2.norm() < 1000, "fault_accel_mps2",
          "must be three finite values below 1000 m/s^2");
}

void CameraSimConfig::load(const ConfigNode& n) {
  n.get("enabled", enabled).get("model", model).get("width", width).get("height", height);
  n.get("fx", fx).get("fy", fy).get("cx", cx).get("cy", cy).get("distortion", distortion);
  n.get("max_angle_deg", max_angle_deg).get("rate_hz", rate_hz).get("phase_s", phase_s);
  n.get("exposure_jitter", exposure_jitter).get("pixel_noise", pixel_noise).get("dropouts_s", dropouts_s);
  n.get("exposure_time_s", exposure_time_s).get("exposure_steps", exposure_steps).get("vignetting", vignetting);
  n.get("stamp_delay_s", stamp_delay_s);
}

Eigen::Isometry3d ExtrinsicsConfig::defaultCamera() {
  const double a[7] = {0.0, 0.0, 0.0, -0.5, 0.5, -0.5, 0.5};
  return poseFromArray(a);
}

void ExtrinsicsConfig::load(const ConfigNode& n) {
  n.get("T_imu_lidar", T_imu_lidar).get("T_imu_camera", T_imu_camera);
}

void SimScenario::load(const ConfigNode& root) {
  root.get("seed", seed).get("duration_s", duration_s).get("start_time_s", start_time_s);
  root.get("environment", environment);
  world.load(root.section("world"));
  trajectory.load(root.section("trajectory"));
  lidar.load(root.section("lidar"));
  imu.load(root.section("imu"));
  camera.load(root.section("camera"));
  extrinsics.load(root.section("extrinsics"));
  rig_map.load(root.section("rig_map"));
}

std::string SimScenario::environmentOrDefault() const {
  if (!environment.empty()) return environment;
  return world.kind == "street" ? "outdoor" : "indoor";
}

namespace {

struct Checker {
  const std::string& source;
  void operator()(bool ok, const std::string& key, const std::string& what) const {
    if (!ok) throw ConfigError(source + ": " + key + ": " + what);
  }
};

void checkRigMap(const Checker& check, const RigMapConfig& m) {
  for (const auto& [key, field] : RigMapConfig::kKeys)
    check(m.*field >= 0.0 && m.*field < 1e7, std::string("rig_map.") + key, "must be in [0, 1e7) m (0: the map's default)");
}

bool oneOf(const std::string& v, std::initializer_list<const char*> options) {
  for (const char* o : options)
    if (v == o) return true;
  return false;
}

}  // namespace

void SimScenario::validate() const {
  const Checker check{source};
  check(seed >= 0, "seed", "must be >= 0");
  check(duration_s > 0.0 && duration_s <= 1e6, "duration_s", "must be in (0, 1e6] s");
  check(start_time_s >= 0.0 && start_time_s < 9e9, "start_time_s", "must be in [0, 9e9) s");
  checkRigMap(check, rig_map);
  check(environment.empty() || oneOf(environment, {"indoor", "outdoor"}), "environment",
        "must be indoor or outdoor, got '" + environment + "'");

  check(oneOf(world.kind, {"room", "corridor", "street", "wall"}), "world.kind",
        "must be room, corridor, street or wall, got '" + world.kind + "'");
  check(world.size_m.minCoeff() > 0.0, "world.size_m", "all sizes must be > 0");
  check(oneOf(world.texture, {"noise", "images", "none"}), "world.texture",
        "must be noise, images or none, got '" + world.texture + "'");
  check(world.texture != "images" || !world.texture_images.empty(), "world.texture_images",
        "texture: images needs at least one image path");
  check(world.texture_tile_m > 0.0, "world.texture_tile_m", "must be > 0");
  check(world.texture_scale_m > 0.0, "world.texture_scale_m", "must be > 0");
  check(world.clutter >= 0.0 && world.clutter <= 1.0, "world.clutter", "must be in [0, 1]");
  check(world.seed >= -1, "world.seed", "must be >= 0 (or -1: the scenario's seed)");
  check(std::isfinite(world.repeat_m) && (world.repeat_m == 0.0 || world.repeat_m >= 20.0), "world.repeat_m",
        "must be 0 (no repeat) or at least 20 m");

  for (const auto& [key, iv] : {std::make_pair("lidar.dropouts_s", &lidar.dropouts_s),
                                std::make_pair("lidar.freeze_s", &lidar.freeze_s),
                                std::make_pair("imu.fault_s", &imu.fault_s),
                                std::make_pair("camera.dropouts_s", &camera.dropouts_s)}) {
    check(iv->size() % 2 == 0, key, "must be pairs [t0, t1, t0, t1, ...]");
    for (std::size_t i = 0; i + 1 < iv->size(); i += 2)
      check(std::isfinite((*iv)[i]) && (*iv)[i] >= 0 && (*iv)[i + 1] > (*iv)[i], key,
            "every interval must have 0 <= t0 < t1 (seconds from the start)");
  }

  const auto& tr = trajectory;
  check(oneOf(tr.kind, {"loop", "lissajous", "waypoints"}), "trajectory.kind",
        "must be loop, lissajous or waypoints, got '" + tr.kind + "'");
  check(tr.speed_mps > 0.0 && tr.speed_mps < 100.0, "trajectory.speed_mps", "must be in (0, 100)");
  check(tr.max_rot_dps > 1.0, "trajectory.max_rot_dps", "must be > 1");
  check(tr.max_accel_mps2 > 0.0, "trajectory.max_accel_mps2", "must be > 0");
  check(tr.static_s >= 0.0, "trajectory.static_s", "must be >= 0");
  // ramp_s 0 only with static_s 0: cruise from the first sample (a start in motion); a ramp of 0 after
  // a rest would be a velocity step.
  check(tr.ramp_s > 0.0 || (tr.ramp_s == 0.0 && tr.static_s == 0.0), "trajectory.ramp_s",
        "must be > 0 (or 0 together with static_s: 0, moving from the first sample)");
  check(tr.size_m.minCoeff() >= 0.0, "trajectory.size_m", "must be >= 0");
  check(tr.height_m >= 0.0, "trajectory.height_m", "must be >= 0");
  check(tr.corner_radius_m >= 0.0, "trajectory.corner_radius_m", "must be >= 0");
  for (int i = 0; i < 3; ++i)
    check(tr.frequencies[i] >= 1.0 && std::floor(tr.frequencies[i]) == tr.frequencies[i] && tr.frequencies[i] <= 20,
          "trajectory.frequencies", "must be integers in [1, 20] (the path must close)");
  check(tr.kind != "waypoints" || (tr.waypoints.size() % 3 == 0 && tr.waypoints.size() >= 9),
        "trajectory.waypoints", "needs x, y, z triples of at least 3 points");
  check(tr.look_at.empty() || tr.look_at.size() == 3, "trajectory.look_at", "expected [x, y, z]");
  check(tr.motion.empty() || oneOf(tr.motion, {"handheld", "car", "drone"}), "trajectory.motion",
        "must be handheld, car or drone, got '" + tr.motion + "'");
  check(!tr.sway_deg || (*tr.sway_deg >= 0.0 && *tr.sway_deg <= 20.0), "trajectory.sway_deg", "must be in [0, 20]");
  check(!tr.bob_m || (*tr.bob_m >= 0.0 && *tr.bob_m <= 0.5), "trajectory.bob_m", "must be in [0, 0.5]");
  check(std::abs(tr.pitch_deg) <= 45.0, "trajectory.pitch_deg", "must be in [-45, 45]");

  check(oneOf(lidar.model, {"avia", "mid360", "spinning32"}), "lidar.model",
        "must be avia, mid360 or spinning32, got '" + lidar.model + "'");
  check(lidar.rate_hz >= 1.0 && lidar.rate_hz <= 50.0, "lidar.rate_hz", "must be in [1, 50]");
  check(lidar.range_noise_m >= 0.0 && lidar.range_noise_m < 1.0, "lidar.range_noise_m", "must be in [0, 1)");
  check(lidar.beam_noise_deg >= 0.0 && lidar.beam_noise_deg < 5.0, "lidar.beam_noise_deg", "must be in [0, 5)");
  check(lidar.max_range_m > 0.0, "lidar.max_range_m", "must be > 0");
  check(lidar.blind_m >= 0.0 && lidar.blind_m < lidar.max_range_m, "lidar.blind_m", "must be in [0, max_range_m)");
  check(lidar.max_incidence_deg > 0.0 && lidar.max_incidence_deg <= 90.0, "lidar.max_incidence_deg",
        "must be in (0, 90]");
  check(lidar.points_per_second >= 0.0 && lidar.points_per_second <= 5e6, "lidar.points_per_second",
        "must be in [0, 5e6] (0: model default)");
  check(lidar.beam_divergence_mrad >= 0.0, "lidar.beam_divergence_mrad", "must be >= 0");

  check(imu.rate_hz >= 10.0 && imu.rate_hz <= 10000.0, "imu.rate_hz", "must be in [10, 10000]");
  check(imu.gyro_noise >= 0.0 && imu.accel_noise >= 0.0, "imu.gyro_noise", "noise densities must be >= 0");
  check(imu.gyro_bias_walk >= 0.0 && imu.accel_bias_walk >= 0.0, "imu.gyro_bias_walk", "bias walks must be >= 0");

  if (camera.enabled) {
    const auto& c = camera;
    check(oneOf(c.model, {"pinhole", "equidistant"}), "camera.model",
          "must be pinhole or equidistant, got '" + c.model + "'");
    check(c.width >= 8 && c.width <= 8192, "camera.width", "must be in [8, 8192]");
    check(c.height >= 8 && c.height <= 8192, "camera.height", "must be in [8, 8192]");
    check(c.fx > 0.0 && c.fy > 0.0, "camera.fx", "focal lengths must be > 0");
    check(c.distortion.size() == 4, "camera.distortion", "expected 4 coefficients");
    check(c.max_angle_deg > 0.0 && c.max_angle_deg < 180.0, "camera.max_angle_deg", "must be in (0, 180)");
    check(c.rate_hz > 0.0 && c.rate_hz <= 200.0, "camera.rate_hz", "must be in (0, 200]");
    check(c.phase_s >= 0.0, "camera.phase_s", "must be >= 0");
    check(c.exposure_jitter >= 0.0 && c.exposure_jitter <= 1.0, "camera.exposure_jitter", "must be in [0, 1]");
    check(c.pixel_noise >= 0.0 && c.pixel_noise <= 100.0, "camera.pixel_noise", "must be in [0, 100]");
    // The exposure cannot outlast the frame interval.
    check(std::isfinite(c.exposure_time_s) && c.exposure_time_s >= 0.0 && c.exposure_time_s < 1.0 / c.rate_hz,
          "camera.exposure_time_s", "must be >= 0 and shorter than the frame interval 1 / rate_hz");
    check(c.exposure_steps.size() % 2 == 0, "camera.exposure_steps", "must be pairs [t, factor, t, factor, ...]");
    for (std::size_t i = 0; i + 1 < c.exposure_steps.size(); i += 2) {
      check(std::isfinite(c.exposure_steps[i]) && c.exposure_steps[i] >= 0.0 &&
                (i == 0 || c.exposure_steps[i] > c.exposure_steps[i - 2]),
            "camera.exposure_steps", "times must be >= 0 and increasing (seconds from the start)");
      check(std::isfinite(c.exposure_steps[i + 1]) && c.exposure_steps[i + 1] > 0.0 && c.exposure_steps[i + 1] <= 100.0,
            "camera.exposure_steps", "every factor must be in (0, 100]");
    }
    check(c.vignetting >= 0.0 && c.vignetting < 1.0, "camera.vignetting", "must be in [0, 1)");
    check(std::isfinite(c.stamp_delay_s) && c.stamp_delay_s >= 0.0 && c.stamp_delay_s <= std::min(0.1, 0.5 / c.rate_hz),
          "camera.stamp_delay_s", "must be in [0, min(0.1 s, half the frame interval)]");
  }
}

namespace {

std::string parentDir(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

SimScenario fromFile(const ConfigFile& file, const std::string& base_dir) {
  SimScenario s;
  s.source = file.name();
  s.base_dir = base_dir;
  s.load(file.root());
  file.checkAllKeysUsed();
  s.validate();
  return s;
}

}  // namespace

SimScenario loadScenarioFile(const std::string& path) {
  return fromFile(ConfigFile::load(path), parentDir(path));
}

SimScenario parseScenario(const std::string& yaml, const std::string& base_dir) {
  return fromFile(ConfigFile::parse(yaml, "<scenario>"), base_dir);
}

}  // namespace livo::sim
