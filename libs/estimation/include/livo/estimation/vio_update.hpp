// Sequential photometric ESIKF update (docs/algorithms.md section 4), run after the LiDAR update at the
// same time stamp: coarse-to-fine over the patch pyramid levels, the reference patch warped into the
// current view by the affine map of its plane, inverse exposure time estimated in the state, an
// iteration that raises the photometric error rolled back, outliers gated.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/worker_pool.hpp"
#include "livo/estimation/state.hpp"
#include "livo/map/visual_point.hpp"
#include "livo/sensors/camera_model.hpp"

#include <vector>

namespace livo {

struct VioConfig {
  int max_iterations = 5;          ///< per pyramid level
  double pixel_noise = 3.0;        ///< sensor noise sigma, gray levels (camera.pixel_noise)
  /// Photometric model error added in quadrature to the sensor noise, gray levels: bilinear sampling,
  /// the affine warp and lighting make patches differ by more than the pixel noise. FAST-LIVO2's
  /// img_point_cov 100 is a sigma of 10. On the simulator 8 beats the bare pixel noise (2): room
  /// 6.1 -> 4.8 mm, corridor 7.2 -> 3.8 mm, street 10.7 -> 5.5 cm ATE.
  double model_noise = 8.0;
  double outlier_rms = 30.0;       ///< a point whose level-0 RMS error exceeds this is not used, gray levels
  bool estimate_exposure = true;   ///< tau in the state (else held)
  bool normal_warp = true;         ///< affine warp from the plane normal (else identity)
  double converge_rot_deg = 0.001;
  double converge_pos_m = 1e-5;
  /// camera.estimate_time_offset: t_d (NavState::time_offset_s) in the update, prior sigma
  /// camera.time_offset_sigma_s, which must stay below half the image interval (camera.rate_hz).
  bool estimate_time_offset = false;
  double time_offset_sigma_s = 0.005;
  double camera_rate_hz = 10.0;    ///< camera.rate_hz: nominal image rate (the offset's bounds)

  /// Reads the `vio` section.
  void load(const ConfigNode& root);
  /// The camera's keys the update uses (pixel_noise, estimate_time_offset, time_offset_sigma_s, rate_hz:
  /// read and checked once, by CameraConfig).
  void takeCamera(const CameraConfig& camera);
  /// Residual variance used by the update, gray levels^2.
  double residualVariance() const { return pixel_noise * pixel_noise + model_noise * model_noise; }
};

struct VioUpdateResult {
  int points_used = 0;             ///< points that passed the gates
  int points_rejected = 0;         ///< gated as outliers or unusable (warp/border)
  int iterations = 0;              ///< over all levels
  int rollbacks = 0;               ///< iterations reverted because the error rose
  double rms_before = 0.0;         ///< level-0 RMS photometric error at the prior, gray levels
  double rms_after = 0.0;          ///< at the posterior
  std::vector<double> point_rms;   ///< per input point, level-0 RMS after the update (-1: not used)
  std::vector<Vec2> point_px;      ///< per input point, its pixel in the current image at the posterior
};

/// The body's motion at the image time, for an image captured t_d = x.time_offset_s after the state's
/// time: angular rate (IMU frame, bias removed) and the state's velocity. The camera is taken to move
/// uniformly over t_d: T_world_imu(capture) = [R Exp(omega t_d), p + v t_d].
struct CaptureMotion {
  Vec3 omega_imu = Vec3::Zero();
};
/// The IMU pose at the capture time (x.pose() exactly when t_d = 0).
Pose imuPoseAtCapture(const NavState& x, const CaptureMotion& m);

/// One residual of a patch pixel: r = tau_k I_k(u) - tau_r P_ref, and its row d r / d [dtheta, dp, dtau]
/// (and, with `H_td`, d r / d t_d), the current pixel at the capture pose (imuPoseAtCapture with
/// `motion`; without it, zero angular rate). Exposed for the Jacobian tests. Returns false when a sample falls
/// outside the image or the crop.
bool photometricResidual(const NavState& x, const Image& gray, const CameraModel& cam, const Pose& T_imu_camera,
                         const VisualPoint& p, const Eigen::Matrix2d& A_ref_from_cur, int level, int row, int col,
                         double& r, Eigen::Matrix<double, 1, 7>* H, const CaptureMotion* motion = nullptr,
                         double* H_td = nullptr);

/// The normal equations the update builds from `points` (each with a reference observation) at state x
/// on one pyramid level: over every usable patch pixel, H^T H inv_var, H^T r inv_var, sum r^2 and the
/// pixel count, H and r as in photometricResidual (the exposure column zeroed unless `exposure`).
/// Exposed for the tests: they compare it with the sum of photometricResidual's rows.
struct PhotometricNormalEquations {
  Eigen::Matrix<double, 7, 7> HtRH = Eigen::Matrix<double, 7, 7>::Zero();
  Eigen::Matrix<double, 7, 1> HtRz = Eigen::Matrix<double, 7, 1>::Zero();
  double cost = 0.0;
  std::size_t pixels = 0;
};
PhotometricNormalEquations photometricNormalEquations(const NavState& x, const Image& gray, const CameraModel& cam,
                                                      const Pose& T_imu_camera, const std::vector<const VisualPoint*>& points,
                                                      const std::vector<Eigen::Matrix2d>& warps, int level,
                                                      double inv_var, bool exposure);
/// Affine map of pixel displacements from the current image to the reference one, d px_ref / d px_cur,
/// from the point's plane (position + normal), by central differences through both camera models.
/// Identity when the plane is seen edge-on or a projection fails.
Eigen::Matrix2d warpRefFromCur(const VisualPoint& p, const VisualObservation& ref, const Pose& T_world_camera,
                               const CameraModel& cam);

/// Runs the update. `points` come from the visual map's retrieval (each with a reference). With
/// `pool`, the per-point work (warps, gates, patch sums) runs on its threads in fixed blocks summed in
/// block order: the result is the same for every thread count, and the same as without a pool.
/// The image was captured at the state's time + x.time_offset_s (`motion`); with
/// cfg.estimate_time_offset the update estimates that offset with the pose.
VioUpdateResult visualUpdate(NavState& x, StateCov& P, const Image& gray, const CameraModel& cam,
                             const Pose& T_imu_camera, const std::vector<VisualPoint*>& points, const VioConfig& cfg,
                             WorkerPool* pool = nullptr, const CaptureMotion& motion = {});

}  // namespace livo
