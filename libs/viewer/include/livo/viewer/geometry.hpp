// Geometry of the drawing: the camera frustum at the latest pose, and where the view's camera goes
// (follow: behind and above the latest pose, turning with its heading; top: straight down over
// everything drawn, parallel projection). Camera frame convention of the suite: x right, y down, z
// along the optical axis.
#pragma once

#include "livo/common/so3.hpp"

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace livo::viewer {

/// Pinhole intrinsics (pixels) of the frustum; width == 0: no camera.
struct FrustumIntrinsics {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  bool valid() const { return width > 0 && height > 0 && fx > 0 && fy > 0; }
};

/// The optical centre and the four image corners (top-left, top-right, bottom-right, bottom-left) at
/// `depth_m` along the optical axis, in the world: what a pinhole camera at T_world_cam sees.
std::array<Vec3, 5> frustumCorners(const FrustumIntrinsics& k, const Pose& T_world_cam, double depth_m);
/// Segments of the frustum drawing as index pairs into frustumCorners(): centre to each corner, and
/// the image rectangle.
const std::vector<std::pair<int, int>>& frustumSegments();

enum class ViewMode { kFollow, kTop, kFree };
/// "follow", "top", "free".
std::string viewModeName(ViewMode m);
bool parseViewMode(const std::string& name, ViewMode& out);
/// follow -> top -> free -> follow.
ViewMode nextViewMode(ViewMode m);

/// A view camera: position, the point it looks at, its up direction; parallel projection with
/// `parallel_scale` (half the height of the view, m) or perspective with `view_angle_deg` (vertical).
struct ViewCamera {
  Vec3 position = Vec3(0, 0, 10), focal = Vec3::Zero(), up = Vec3::UnitY();
  bool parallel = false;
  double parallel_scale = 10.0;
  double view_angle_deg = 45.0;
};

struct FollowConfig {
  double distance_m = 6.0;      ///< behind the pose, along its heading (horizontal)
  double height_m = 4.0;        ///< above the pose
  double look_ahead_m = 1.0;    ///< focal point ahead of the pose
  double heading_tau_s = 0.7;   ///< time constant of the heading's smoothing (message time), s
};

/// Follow camera with a smoothed heading (the yaw of the body x axis), so that the handheld sway does
/// not shake the view. Time is message time.
class FollowCamera {
 public:
  explicit FollowCamera(FollowConfig cfg = {}) : cfg_(cfg) {}
  /// The camera for the pose at time t_s (the first call, or a call after reset(), jumps to the pose).
  ViewCamera update(const Pose& T_world_imu, double t_s);
  void reset() { started_ = false; }
  double heading() const { return heading_; }

 private:
  FollowConfig cfg_;
  bool started_ = false;
  double heading_ = 0.0, last_t_ = 0.0;
};

/// The box holding all but the fraction `q` of `points` at each end of each axis (a few far outliers do
/// not shrink the top view); `lo` = `hi` = 0 for no points.
void robustBounds(const std::vector<Eigen::Vector3f>& points, double q, Vec3& lo, Vec3& hi);

/// Straight-down parallel view (x right, y up on the screen) covering the box [lo, hi] with a margin
/// (fraction of the larger side) in a window of aspect width / height, below the top `top_reserve`
/// fraction of the window's height (kept free for the text overlay).
ViewCamera topCamera(const Vec3& lo, const Vec3& hi, double aspect, double margin = 0.08, double top_reserve = 0.0);

}  // namespace livo::viewer
