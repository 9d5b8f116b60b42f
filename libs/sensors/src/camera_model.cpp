// CameraModel base: validation, the factory with the image scale, and the undistorted pinhole Jacobian.
#include "livo/sensors/camera_model.hpp"

#include <cmath>
#include <stdexcept>

namespace livo {

namespace {

void require(bool ok, const std::string& field, const std::string& what) {
  if (!ok) throw std::invalid_argument("camera model: " + field + ": " + what);
}

}  // namespace

Eigen::Matrix<double, 2, 3> projectionJacobianPinhole(const Eigen::Vector3d& p_cam, double fx, double fy) {
  const double iz = 1.0 / p_cam.z();
  Eigen::Matrix<double, 2, 3> J;
  J << fx * iz, 0.0, -fx * p_cam.x() * iz * iz,  //
      0.0, fy * iz, -fy * p_cam.y() * iz * iz;
  return J;
}

CameraModel::CameraModel(int width, int height, double fx, double fy, double cx, double cy,
                         const std::array<double, 4>& d)
    : width_(width), height_(height), fx_(fx), fy_(fy), cx_(cx), cy_(cy), d_(d) {
  require(width > 0 && height > 0, "width/height", "must be positive, got " + std::to_string(width) + "x" +
                                                       std::to_string(height));
  require(std::isfinite(fx) && fx > 0, "fx", "must be finite and > 0");
  require(std::isfinite(fy) && fy > 0, "fy", "must be finite and > 0");
  require(std::isfinite(cx) && std::isfinite(cy), "cx/cy", "must be finite");
  for (double k : d) require(std::isfinite(k), "distortion", "coefficients must be finite");
}

Eigen::Matrix3d CameraModel::K() const {
  Eigen::Matrix3d K;
  K << fx_, 0, cx_, 0, fy_, cy_, 0, 0, 1;
  return K;
}

std::unique_ptr<CameraModel> CameraModel::create(const CameraConfig& cfg) {
  require(std::isfinite(cfg.scale) && cfg.scale > 0, "scale", "must be finite and > 0");
  require(cfg.distortion.empty() || cfg.distortion.size() == 4, "distortion",
          "needs 4 coefficients (or none), got " + std::to_string(cfg.distortion.size()));
  std::array<double, 4> d{0, 0, 0, 0};
  for (size_t i = 0; i < cfg.distortion.size(); ++i) d[i] = cfg.distortion[i];
  // Scale (see the header): cv::resize(src, dst, Size(), s, s) maps x -> (x + 0.5) s - 0.5.
  const double s = cfg.scale;
  const int w = static_cast<int>(std::lround(cfg.width * s));
  const int h = static_cast<int>(std::lround(cfg.height * s));
  const double fx = cfg.fx * s, fy = cfg.fy * s;
  const double cx = (cfg.cx + 0.5) * s - 0.5, cy = (cfg.cy + 0.5) * s - 0.5;
  switch (cfg.model) {
    case CameraKind::Pinhole: return std::make_unique<PinholeRadtan>(w, h, fx, fy, cx, cy, d);
    case CameraKind::Equidistant: return std::make_unique<Equidistant>(w, h, fx, fy, cx, cy, d);
  }
  require(false, "model", "is not a camera model");
  return nullptr;
}

}  // namespace livo
