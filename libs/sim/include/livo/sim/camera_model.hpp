// Camera projection of the simulator: pinhole with radial-tangential distortion (k1 k2 p1 p2) and
// equidistant fisheye (Kannala-Brandt k1..k4). Camera frame: x right, y down, z along the optical axis.
// Pixel (u, v) = (column, row) with integer values at pixel centres (OpenCV convention).
#pragma once

#include "livo/common/so3.hpp"
#include "livo/sim/scenario.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace livo::sim {

class SimCameraModel {
 public:
  explicit SimCameraModel(const CameraSimConfig& cfg);

  /// Projects a point in the camera frame; false behind the camera / outside the model's domain.
  bool project(const Vec3& p_cam, Eigen::Vector2d& uv) const;
  /// Unit ray of a pixel position (Newton inversion of the distortion); false when it does not converge.
  bool unproject(const Eigen::Vector2d& uv, Vec3& ray) const;

  int width() const { return cfg_.width; }
  int height() const { return cfg_.height; }
  /// Precomputed unit ray per pixel (row-major); valid()[i] is false for pixels outside the model
  /// (beyond max_angle_deg for fisheye) which render black.
  const std::vector<Eigen::Vector3f>& rays() const { return rays_; }
  const std::vector<std::uint8_t>& valid() const { return valid_; }
  /// Angular size of each pixel, radians (texture footprint per metre of distance).
  const std::vector<float>& pixelAngle() const { return pixel_angle_; }

 private:
  void distort(double x, double y, double& xd, double& yd) const;  // pinhole, normalised coordinates
  CameraSimConfig cfg_;
  bool fisheye_ = false;
  std::vector<Eigen::Vector3f> rays_;
  std::vector<std::uint8_t> valid_;
  std::vector<float> pixel_angle_;
};

}  // namespace livo::sim
