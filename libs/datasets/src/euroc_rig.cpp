// Rig config snippet (config/README.md: sections imu and camera) from an EuRoC calibration.
#include "livo/datasets/euroc.hpp"

#include <cstdio>
#include <sstream>

namespace livo {

namespace {
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  return buf;
}
std::string list(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + num(v[i]);
  return s + "]";
}
}  // namespace

std::string eurocRigYaml(const EurocCalibration& c, const std::string& source) {
  const Eigen::Isometry3d T = c.T_imu_camera();
  Eigen::Quaterniond q(T.rotation());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;  // one sign convention: qw >= 0
  const Eigen::Vector3d t = T.translation();

  std::ostringstream os;
  os << "# Rig config written by livo-convert euroc from the sensor.yaml files in\n"
     << "# " << source << "\n"
     << "# Body = IMU frame: T_imu_camera = inv(T_BS of the IMU) * T_BS of the camera.\n"
     << "# There is no LiDAR in EuRoC: the lidar section is intentionally absent (visual-inertial data).\n"
     << "# Keys and units: config/README.md.\n"
     << "imu:\n"
     << "  rate_hz: " << num(c.imu.rate_hz) << "\n"
     << "  gyro_noise: " << num(c.imu.gyro_noise) << "  # rad/s/sqrt(Hz)\n"
     << "  accel_noise: " << num(c.imu.accel_noise) << "  # m/s^2/sqrt(Hz)\n"
     << "  gyro_bias_walk: " << num(c.imu.gyro_bias_walk) << "  # rad/s^2/sqrt(Hz)\n"
     << "  accel_bias_walk: " << num(c.imu.accel_bias_walk) << "  # m/s^3/sqrt(Hz)\n"
     << "\n"
     << "camera:\n"
     << "  enabled: true\n"
     << "  model: " << toString(c.camera.model) << "  # distortion: "
     << (c.camera.model == CameraKind::Pinhole ? "radtan [k1, k2, p1, p2]" : "Kannala-Brandt [k1, k2, k3, k4]") << "\n"
     << "  width: " << c.camera.width << "\n"
     << "  height: " << c.camera.height << "\n"
     << "  fx: " << num(c.camera.fx) << "\n"
     << "  fy: " << num(c.camera.fy) << "\n"
     << "  cx: " << num(c.camera.cx) << "\n"
     << "  cy: " << num(c.camera.cy) << "\n"
     << "  distortion: " << list(c.camera.distortion) << "\n"
     << "  T_imu_camera: " << list({t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()})
     << "  # [x, y, z, qx, qy, qz, qw]\n";
  return os.str();
}

}  // namespace livo
