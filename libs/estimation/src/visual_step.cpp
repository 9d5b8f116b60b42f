#include "livo/estimation/visual_step.hpp"

#include <cmath>

namespace livo {

std::vector<Vec3> scanInWorld(const NavState& x, const std::vector<BodyPoint>& points) {
  std::vector<Vec3> out;
  out.reserve(points.size());
  for (const auto& bp : points) out.push_back(x.R_world_imu * bp.p_imu + x.p_world_imu);
  return out;
}

VisualStepResult runVisualStep(const FrameVisualMap& map, NavState& x, StateCov& P, const Image& gray, const CameraModel& cam,
                               const Pose& T_imu_camera, const VioConfig& vio, Utime t, const LioFrameResult& lio,
                               const NoScanRetrieval* no_scan, WorkerPool* pool, const CaptureMotion& motion) {
  VisualStepResult r;
  DualVisualMap& visual = *map.visual;
  // Retrieval: visual points in the voxels of the current scan (or of the camera frustum when the
  // LiDAR failed), one per grid cell, not occluded, seen from the camera at its capture time.
  VisualRetrieval got = visual.retrieve(cam, imuPoseAtCapture(x, motion) * T_imu_camera, scanInWorld(x, lio.points),
                                        no_scan ? &no_scan->frustum_keys : nullptr);
  r.points = std::move(got.points);

  // Photometric update, sequential after the LiDAR one at the same time stamp.
  if (!r.points.empty()) r.update = visualUpdate(x, P, gray, cam, T_imu_camera, r.points, vio, pool, motion);
  const VioUpdateResult& vu = r.update;

  // Visual map at the posterior: errors, new observations, references/normals, new points.
  const Pose T_world_camera = imuPoseAtCapture(x, motion) * T_imu_camera;
  const double gate = vio.outlier_rms * vio.outlier_rms;
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    if (vu.point_rms.size() == r.points.size() && vu.point_rms[i] >= 0) {
      r.n_longterm_used += r.points[i]->from_longterm;
      visual.observe(*r.points[i], vu.point_rms[i] * vu.point_rms[i], gate, gray, T_world_camera, vu.point_px[i],
                     float(x.inv_exposure), t, map.planes);
    }
  }
  // Points removed here must not be used through r.points any more. New points go to the cells
  // the retrieval left free.
  r.removed_bad = visual.removeBadPoints();
  if (r.removed_bad > 0) r.points.clear();
  std::vector<NewPointCandidate> candidates;
  if (no_scan != nullptr && map.planes != nullptr)
    candidates = raycastCandidates(*map.planes, cam, T_world_camera, got.grid, got.occupied, no_scan->ray_step_m,
                                   no_scan->min_depth_m, no_scan->max_depth_m);
  candidates.reserve(candidates.size() + lio.matched_index.size());
  const WorldPointCovariance point_cov(x, P);
  for (std::size_t k = 0; k < lio.matched_index.size() && lio.lio_ok; ++k) {  // registered points only
    const BodyPoint& bp = lio.points[static_cast<std::size_t>(lio.matched_index[k])];
    NewPointCandidate c;
    const Vec3 q = x.R_world_imu * bp.p_imu;
    c.p_world = q + x.p_world_imu;
    c.normal_world = lio.matched_normals[k];
    c.cov_world = point_cov(bp, q);
    candidates.push_back(c);
  }
  r.n_new_points = visual.addPoints(gray, cam, T_world_camera, float(x.inv_exposure), t, candidates, got.occupied);
  return r;
}

std::vector<NewPointCandidate> raycastCandidates(const PlaneFinder& planes, const CameraModel& cam,
                                                 const Pose& T_world_camera, const ImageGrid& grid,
                                                 const std::vector<bool>& occupied, double step_m, double min_depth_m,
                                                 double max_depth_m) {
  std::vector<NewPointCandidate> out;
  if (!(step_m > 0) || !(max_depth_m > min_depth_m)) return out;
  const Vec3 c = T_world_camera.translation();
  PointWithCov q;
  q.cov_world = Mat3::Identity() * step_m * step_m;  // the plane gates take the step as the point's sigma
  for (int row = 0; row < grid.rows; ++row) {
    for (int col = 0; col < grid.cols; ++col) {
      const int cell = row * grid.cols + col;
      if (!occupied.empty() && occupied[std::size_t(cell)]) continue;
      const Vec2 px((col + 0.5) * grid.cell_px, (row + 0.5) * grid.cell_px);
      Vec3 bearing;
      if (!cam.unproject(px, bearing) || !(bearing.z() > 1e-6)) continue;
      const Vec3 dir = T_world_camera.linear() * bearing.normalized();
      for (double s = min_depth_m; s <= max_depth_m; s += step_m) {
        q.p_world = c + s * dir;
        PlaneMatch m;
        if (!planes.findBestPlane(q, m) || std::abs(m.distance) > step_m) continue;
        const Plane& pl = *m.plane;
        const double denom = pl.normal.dot(dir);
        if (std::abs(denom) < 0.1) break;  // grazing: the intersection is ill-defined
        const double t_hit = -(pl.normal.dot(c) + pl.d) / denom;
        if (t_hit < min_depth_m || t_hit > max_depth_m) break;
        NewPointCandidate cand;
        cand.p_world = c + t_hit * dir;
        cand.normal_world = pl.normal;
        cand.cov_world = pl.cov_nq.bottomRightCorner<3, 3>() + Mat3::Identity() * 1e-4;
        out.push_back(cand);
        break;
      }
    }
  }
  return out;
}

}  // namespace livo
