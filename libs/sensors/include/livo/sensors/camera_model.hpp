// Camera models: projection of camera-frame points to pixels, its analytic Jacobian, and the inverse
// (pixel -> unit bearing). No OpenCV and no allocation on the per-point paths.
//
// Conventions
// - Camera frame: x right, y down, z forward (optical axis). Pixel (u, v): u = column, v = row.
// - Pixel centres sit at integer coordinates (OpenCV's convention): the top-left pixel's centre is (0, 0)
//   and the image covers [-0.5, width - 0.5] x [-0.5, height - 0.5].
// - Image scale s (CameraConfig::scale): the visual update works on the image resized by s with
//   cv::resize(src, dst, cv::Size(), s, s), which maps a source coordinate x to (x + 0.5) s - 0.5.
//   Hence the scaled camera has  size = round(size * s),  f' = f s,  c' = (c + 0.5) s - 0.5,
//   and distortion unchanged (it acts on normalised coordinates). FAST-LIVO2 (vikit) uses c' = c s
//   instead, i.e. the corner convention: that differs by 0.5 (1 - s) px (0.25 px at s = 0.5).
//
// Models (both are OpenCV's, and agree with cv::projectPoints / cv::fisheye::projectPoints to 1e-9 px):
// - PinholeRadtan (cv::projectPoints with [k1, k2, p1, p2]; vikit "Pinhole"):
//     x = X/Z, y = Y/Z, r^2 = x^2 + y^2, g = 1 + k1 r^2 + k2 r^4
//     x_d = x g + 2 p1 x y + p2 (r^2 + 2 x^2),  y_d = y g + p1 (r^2 + 2 y^2) + 2 p2 x y          (1)
//     u = fx x_d + cx,  v = fy y_d + cy                                                            (2)
//   Valid for Z > 0 and r below the first radius where the radial map r -> r g(r) stops increasing
//   (1 + 3 k1 r^2 + 5 k2 r^4 = 0); beyond it the model folds back and points would alias into the image.
// - Equidistant / Kannala-Brandt (cv::fisheye; vikit "EquidistantCamera"):
//     r = sqrt(X^2 + Y^2), theta = atan2(r, Z)  (angle from the optical axis, 0..pi)
//     theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)                      (3)
//     x_d = theta_d X / r,  y_d = theta_d Y / r,  then (2).
//   Valid for theta < maxAngle(): the first angle where theta_d(theta) stops increasing, capped at
//   179 deg. Unlike the reference (z > 0 only) this includes points behind the image plane (theta > 90 deg)
//   when the calibration polynomial allows it; unproject() then returns a bearing with z <= 0, so treat
//   bearings as rays (c + t * bearing), never divide by their z.
//
// Inverse: unproject() solves the distortion by safeguarded Newton iterations until the residual is below
// 1e-12 in normalised units (~1e-9 px) and reports false when it does not converge or the solution lies
// outside the valid region (no fixed iteration count).
#pragma once

#include "livo/sensors/camera_config.hpp"

#include <Eigen/Core>

#include <array>
#include <memory>
#include <string>

namespace livo {

/// d(u, v) / d p_cam of the undistorted pinhole u = fx X/Z + cx, v = fy Y/Z + cy (the reference's
/// Jacobian for every camera; the real models below return their own through project()).
Eigen::Matrix<double, 2, 3> projectionJacobianPinhole(const Eigen::Vector3d& p_cam, double fx, double fy);

class CameraModel {
 public:
  virtual ~CameraModel() = default;

  /// Builds the model named by cfg.model (pinhole | equidistant) with cfg.scale applied (see the header
  /// comment). Missing distortion means zeros. Throws std::invalid_argument naming the field on bad values.
  static std::unique_ptr<CameraModel> create(const CameraConfig& cfg);

  int width() const { return width_; }
  int height() const { return height_; }
  double fx() const { return fx_; }
  double fy() const { return fy_; }
  double cx() const { return cx_; }
  double cy() const { return cy_; }
  /// Intrinsic matrix [fx 0 cx; 0 fy cy; 0 0 1].
  Eigen::Matrix3d K() const;
  /// The 4 distortion coefficients ([k1, k2, p1, p2] or [k1, k2, k3, k4]).
  const std::array<double, 4>& distortion() const { return d_; }

  /// p_cam -> pixel; J (optional) = d px / d p_cam including distortion. False (px, J unspecified) when
  /// the point is outside the model's valid region (behind the camera / beyond the valid radius or angle).
  /// The pixel may lie outside the image: check inImage().
  virtual bool project(const Eigen::Vector3d& p_cam, Eigen::Vector2d& px,
                       Eigen::Matrix<double, 2, 3>* J = nullptr) const = 0;
  /// pixel -> unit bearing in the camera frame. False when the pixel has no valid ray.
  virtual bool unproject(const Eigen::Vector2d& px, Eigen::Vector3d& bearing) const = 0;
  /// True when px is at least border_px away from the outermost pixel centres:
  /// border <= u <= width - 1 - border and the same for v. With border_px = 0 a bilinear read at px
  /// touches only pixels of the image; for a patch of half-size h read bilinearly use border h + 1.
  bool inImage(const Eigen::Vector2d& px, double border_px) const {
    return px.x() >= border_px && px.y() >= border_px && px.x() <= width_ - 1 - border_px &&
           px.y() <= height_ - 1 - border_px;
  }
  /// One line: model, size, intrinsics, distortion, validity limit.
  virtual std::string describe() const = 0;

 protected:
  CameraModel(int width, int height, double fx, double fy, double cx, double cy, const std::array<double, 4>& d);
  int width_, height_;
  double fx_, fy_, cx_, cy_;
  std::array<double, 4> d_;
};

/// Pinhole with radial-tangential distortion, eqs. (1)-(2); d = [k1, k2, p1, p2].
class PinholeRadtan final : public CameraModel {
 public:
  PinholeRadtan(int width, int height, double fx, double fy, double cx, double cy, const std::array<double, 4>& d);
  bool project(const Eigen::Vector3d& p_cam, Eigen::Vector2d& px,
               Eigen::Matrix<double, 2, 3>* J = nullptr) const override;
  bool unproject(const Eigen::Vector2d& px, Eigen::Vector3d& bearing) const override;
  std::string describe() const override;
  /// Largest valid normalised radius r = |(X, Y)| / Z (1e6 when the radial map never folds).
  double maxRadius() const { return r_max_; }

  /// Eq. (1) on normalised coordinates, with d x_d / d x (2x2) when Jd is given.
  Eigen::Vector2d distort(const Eigen::Vector2d& xy, Eigen::Matrix2d* Jd = nullptr) const;

 private:
  double r_max_, r2_max_;
};

/// Equidistant (Kannala-Brandt) fisheye, eqs. (2)-(3); d = [k1, k2, k3, k4].
class Equidistant final : public CameraModel {
 public:
  Equidistant(int width, int height, double fx, double fy, double cx, double cy, const std::array<double, 4>& d);
  bool project(const Eigen::Vector3d& p_cam, Eigen::Vector2d& px,
               Eigen::Matrix<double, 2, 3>* J = nullptr) const override;
  bool unproject(const Eigen::Vector2d& px, Eigen::Vector3d& bearing) const override;
  std::string describe() const override;
  /// Largest valid angle from the optical axis, radians.
  double maxAngle() const { return theta_max_; }

  /// Eq. (3): theta_d(theta), and d theta_d / d theta when deriv is given.
  double distortAngle(double theta, double* deriv = nullptr) const;

 private:
  double theta_max_, theta_d_max_;
};

}  // namespace livo
