// Step 6 of the per-frame pipeline (frame_pipeline.hpp: photometric update, visual map update),
// written once for the two places a visual map can be: the in-process hybrid map (InProcessMap,
// livo-run) and the estimator's per-frame copy of the visual points the map server sent (RemoteMap,
// livo-estimator).
#pragma once

#include "livo/estimation/lio_odometry.hpp"
#include "livo/estimation/vio_update.hpp"
#include "livo/map/hybrid_map.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/visual_map.hpp"
#include "livo/sensors/camera_config.hpp"
#include "livo/sensors/camera_model.hpp"

#include <vector>

namespace livo {

/// The visual map operations the visual step needs (VisualMap / HybridMap semantics).
class VisualMapOps {
 public:
  virtual ~VisualMapOps() = default;
  /// `voxel_keys` null: the visual voxels of `scan_points_world`; else those keys (see VisualMap).
  virtual std::vector<VisualPoint*> pointsInView(const CameraModel& cam, const Pose& T_world_camera,
                                                 const std::vector<Vec3>& scan_points_world,
                                                 const std::vector<VoxelKey>* voxel_keys) = 0;
  virtual const std::vector<bool>& occupiedCells() const = 0;
  virtual ImageGrid gridFor(const CameraModel& cam) const = 0;
  virtual void reportPhotometricError(VisualPoint& p, double mean_sq_error, double gate) = 0;
  virtual bool addObservation(VisualPoint& p, const Image& gray, const Pose& T_world_camera, const Vec2& px,
                              float inv_exposure, Utime t) = 0;
  virtual void refine(VisualPoint& p) = 0;
  /// The LiDAR planes the map has around the frame (normal refinement, new points by ray casting);
  /// may be null.
  virtual const PlaneFinder* planes() const = 0;
  virtual std::size_t removeBadPoints() = 0;
  virtual int addPoints(const Image& gray, const CameraModel& cam, const Pose& T_world_camera, float inv_exposure,
                        Utime t, const std::vector<NewPointCandidate>& candidates,
                        const std::vector<bool>& occupied_cells) = 0;
};

/// Forwards every VisualMapOps call except refine() to a map with VisualMap's per-frame operations.
template <class Map>
class VisualOpsOn : public VisualMapOps {
 public:
  explicit VisualOpsOn(Map& map) : map_(map) {}
  std::vector<VisualPoint*> pointsInView(const CameraModel& cam, const Pose& T, const std::vector<Vec3>& scan,
                                         const std::vector<VoxelKey>* keys) override {
    return map_.pointsInView(cam, T, scan, nullptr, keys);
  }
  const std::vector<bool>& occupiedCells() const override { return map_.occupiedCells(); }
  ImageGrid gridFor(const CameraModel& cam) const override { return map_.gridFor(cam); }
  void reportPhotometricError(VisualPoint& p, double e, double gate) override { map_.reportPhotometricError(p, e, gate); }
  bool addObservation(VisualPoint& p, const Image& g, const Pose& T, const Vec2& px, float tau, Utime t) override {
    return map_.addObservation(p, g, T, px, tau, t);
  }
  std::size_t removeBadPoints() override { return map_.removeBadPoints(); }
  int addPoints(const Image& g, const CameraModel& cam, const Pose& T, float tau, Utime t,
                const std::vector<NewPointCandidate>& c, const std::vector<bool>& occ) override {
    return map_.addPoints(g, cam, T, tau, t, c, occ);
  }

 protected:
  Map& map_;
};

/// On a HybridMap: both visual maps, refinement against its LiDAR map.
class HybridVisualOps final : public VisualOpsOn<DualVisualMap> {
 public:
  explicit HybridVisualOps(HybridMap& map) : VisualOpsOn(map.visual()), planes_(&map.lidar().voxels()) {}
  void refine(VisualPoint& p) override { map_.refine(p, planes_); }
  const PlaneFinder* planes() const override { return planes_; }

 private:
  const PlaneFinder* planes_;
};

/// On one VisualMap, refining normals against `planes` (may be null).
class SingleVisualOps final : public VisualOpsOn<VisualMap> {
 public:
  SingleVisualOps(VisualMap& map, const PlaneFinder* planes) : VisualOpsOn(map), planes_(planes) {}
  void refine(VisualPoint& p) override { map_.refine(p, planes_); }
  const PlaneFinder* planes() const override { return planes_; }

 private:
  const PlaneFinder* planes_;
};

/// New-point candidates without a registered scan (docs/algorithms.md 5.4, ray casting): for each free
/// cell of the selection grid, the ray through its centre is stepped from min_depth_m to
/// max_depth_m by half a LiDAR voxel; the first step near a LiDAR plane of `planes` gives the ray's
/// intersection with that plane, with the plane's normal.
std::vector<NewPointCandidate> raycastCandidates(const PlaneFinder& planes, const CameraModel& cam,
                                                 const Pose& T_world_camera, const ImageGrid& grid,
                                                 const std::vector<bool>& occupied, double step_m, double min_depth_m,
                                                 double max_depth_m);

/// World points of the frame's body points at state `x`.
std::vector<Vec3> scanInWorld(const NavState& x, const std::vector<BodyPoint>& points);

struct VisualStepResult {
  VioUpdateResult update;
  std::vector<VisualPoint*> points;  ///< the points in view that were used (valid until the map changes)
  int n_new_points = 0;
  std::size_t removed_bad = 0;
  /// Points used by the update that came through the long-term visual map: held by it, or returned from
  /// it to the local map on a revisit (VisualPoint::from_longterm; also known to a remote estimator).
  int n_longterm_used = 0;
};

/// Step 6 at the LiDAR posterior (x, P): retrieval of the points in view of the scan, the
/// photometric update (x, P become its posterior when a point was used), then at the posterior the
/// photometric error bookkeeping, new observations + refinement, removal of bad points and new
/// points from the plane-matched LiDAR points in free cells.
/// Without a registered scan (a frame whose LiDAR update failed): `no_scan` holds the visual voxels
/// of the camera frustum to retrieve from, and new points come from ray casting into the map's
/// planes (raycastCandidates) instead of from the scan.
struct NoScanRetrieval {
  std::vector<VoxelKey> frustum_keys;
  double ray_step_m = 0.25;
  double min_depth_m = 0.1;
  double max_depth_m = 30.0;
};
VisualStepResult runVisualStep(VisualMapOps& map, NavState& x, StateCov& P, const Image& gray, const CameraModel& cam,
                               const Pose& T_imu_camera, const VioConfig& vio, Utime t, const LioFrameResult& lio,
                               const NoScanRetrieval* no_scan = nullptr, WorkerPool* pool = nullptr,
                               const CaptureMotion& motion = {});

}  // namespace livo
