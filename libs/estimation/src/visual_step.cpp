#include "livo/estimation/visual_step.hpp"

#include <cmath>

namespace livo {

std::vector<Vec3> scanInWorld(const NavState& x, const std::vector<BodyPoint>& points) {
  std::vector<Vec3> out;
  out.reserve(points.size());
  for (const auto& bp : points) out.push_back(x.R_world_imu * bp.p_imu + x.p_world_imu);
  return out;
}

VisualStepResult runVisualStep(VisualMapOps& map, NavState& x, StateCov& P, const Image& gray, const CameraModel& cam,
                               const Pose& T_imu_camera, const VioConfig& vio, Utime t, const LioFrameResult& lio) {
  VisualStepResult r;
  // Retrieval: visual points in the voxels of the current scan, one per grid cell, not occluded.
  r.points = map.pointsInView(cam, x.pose() * T_imu_camera, scanInWorld(x, lio.points));

  // Photometric update, sequential after the LiDAR one at the same time stamp.
  if (!r.points.empty()) r.update = visualUpdate(x, P, gray, cam, T_imu_camera, r.points, vio);
  const VioUpdateResult& vu = r.update;

  // Visual map at the posterior: errors, new observations, references/normals, new points.
  const Pose T_world_camera = x.pose() * T_imu_camera;
  const double gate = vio.outlier_rms * vio.outlier_rms;
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    if (vu.point_rms.size() == r.points.size() && vu.point_rms[i] >= 0) {
      map.reportPhotometricError(*r.points[i], vu.point_rms[i] * vu.point_rms[i], gate);
      if (map.addObservation(*r.points[i], gray, T_world_camera, vu.point_px[i], float(x.inv_exposure), t))
        map.refine(*r.points[i]);
    }
  }
  // Points removed here must not be used through r.points any more.
  std::vector<bool> occupied = map.occupiedCells();
  r.removed_bad = map.removeBadPoints();
  if (r.removed_bad > 0) r.points.clear();
  std::vector<NewPointCandidate> candidates;
  candidates.reserve(lio.matched_index.size());
  for (std::size_t k = 0; k < lio.matched_index.size(); ++k) {
    const BodyPoint& bp = lio.points[static_cast<std::size_t>(lio.matched_index[k])];
    NewPointCandidate c;
    c.p_world = x.R_world_imu * bp.p_imu + x.p_world_imu;
    c.normal_world = lio.matched_normals[k];
    c.cov_world = worldPointCovariance(x, P, bp);
    candidates.push_back(c);
  }
  if (occupied.size() != static_cast<std::size_t>(map.gridFor(cam).size())) occupied.clear();
  r.n_new_points = map.addPoints(gray, cam, T_world_camera, float(x.inv_exposure), t, candidates, occupied);
  return r;
}

}  // namespace livo
