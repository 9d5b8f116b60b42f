// VisualMap: observation rules (docs/algorithms.md 5.2), reference selection and normal refinement (5.3),
// outlier bookkeeping (5.5).
#include "livo/map/visual_map.hpp"

#include "livo/map/visual_map_scores.hpp"
#include "livo/map/voxel_map.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace livo {

namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

// Unit vector from the point to the camera centre of an observation.
Vec3 rayToCamera(const VisualPoint& p, const Pose& T_world_camera) {
  const Vec3 d = T_world_camera.translation() - p.p_world;
  const double n = d.norm();
  return n > 0.0 ? Vec3(d / n) : Vec3::Zero();
}

}  // namespace

bool VisualMap::addObservation(VisualPoint& p, const Image& gray, const Pose& T_world_camera, const Vec2& px,
                               float inv_exposure, Utime t) {
  if (gray.format != PixelFormat::Gray8 || gray.row_stride < gray.width ||
      gray.data.size() < std::size_t(std::max(gray.row_stride, 0)) * std::size_t(std::max(gray.height, 0)))
    throw std::invalid_argument("VisualMap::addObservation: image must be Gray8 with row_stride x height bytes");
  p.last_seen = t;
  if (p.converged) return false;  // frozen: only the reference is kept
  if (!px.allFinite() || !T_world_camera.matrix().allFinite()) return false;

  if (!p.obs.empty()) {
    // Compare with the NEWEST observation (obs.back(); the reference code used its oldest).
    const VisualObservation& newest = p.obs.back();
    const double moved = (T_world_camera.translation() - newest.T_world_camera.translation()).norm();
    const double cos_turn = rayToCamera(p, T_world_camera).dot(rayToCamera(p, newest.T_world_camera));
    const double turned = std::acos(std::clamp(cos_turn, -1.0, 1.0));
    const double shift = (px - newest.px).norm();
    if (!(moved > config_.new_obs_min_translation_m || turned > config_.new_obs_min_angle_deg * kDegToRad ||
          shift > config_.new_obs_min_pixel_shift_px))
      return false;
  }

  VisualObservation o;
  if (!extractPatchPyramid(gray, px, o.patch)) return false;
  o.utime = t;
  o.T_world_camera = T_world_camera;
  o.px = px;
  o.inv_exposure = inv_exposure;
  // Grow by doubling but never beyond max_observations + 1 (the new one before a drop): a full point
  // must not sit on a vector of twice the size it can use.
  if (p.obs.size() == p.obs.capacity()) {
    const std::size_t cap_limit = std::size_t(config_.max_observations) + 1;
    p.obs.reserve(std::max(p.obs.size() + 1, std::min(2 * p.obs.size(), cap_limit)));
  }
  p.obs.push_back(o);
  ++p.views;
  if (p.reference < 0 || p.reference >= int(p.obs.size())) p.reference = int(p.obs.size()) - 1;

  // Too many: drop the lowest-scoring observation other than the reference and the new one.
  bool kept_new = true;
  while (int(p.obs.size()) > config_.max_observations) {
    scoreObservations(p);
    const int newest = int(p.obs.size()) - 1;
    int worst = -1;
    for (int i = 0; i < newest; ++i) {
      if (i == p.reference) continue;
      if (worst < 0 || p.obs[std::size_t(i)].score < p.obs[std::size_t(worst)].score) worst = i;
    }
    if (worst < 0) worst = newest;  // only the reference besides the new one (cannot happen for max >= 2)
    if (worst == newest) kept_new = false;
    p.obs.erase(p.obs.begin() + worst);
    if (p.reference > worst) --p.reference;
  }
  return kept_new;
}

int VisualMap::scoreObservations(VisualPoint& p) const {
  const std::size_t n = p.obs.size();
  if (n == 0) return -1;
  std::vector<PatchValues> patches(n);
  for (std::size_t i = 0; i < n; ++i) patches[i] = patchOfLevel(p.obs[i].patch, 0);
  std::vector<double> sum(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      const double c = std::abs(ncc(patches[i], patches[j]));
      sum[i] += c;
      sum[j] += c;
    }
  }
  int best = -1;
  for (std::size_t i = 0; i < n; ++i) {
    const double agreement = n > 1 ? sum[i] / double(n - 1) : 0.0;
    const double view = rayToCamera(p, p.obs[i].T_world_camera).dot(p.normal);
    p.obs[i].score = static_cast<float>(agreement + view);
    if (best < 0 || p.obs[i].score > p.obs[std::size_t(best)].score) best = int(i);
  }
  return best;
}

void VisualMap::refine(VisualPoint& p, const PlaneFinder* lidar_map) {
  if (p.obs.empty()) {
    p.reference = -1;
    return;
  }
  bool normal_settled = false;
  if (!p.converged && lidar_map != nullptr && int(p.obs.size()) >= config_.refine_min_observations) {
    PlaneMatch match;
    PointWithCov query;
    query.p_world = p.p_world;
    query.cov_world = p.cov;
    if (lidar_map->findBestPlane(query, match) && match.plane != nullptr && match.plane->is_plane) {
      Vec3 n = match.plane->normal.normalized();
      if (n.dot(p.normal) < 0.0) n = -n;  // keep the sign of the previous normal (facing the cameras)
      const double dn = (n - p.normal).norm();
      p.normal = n;
      normal_settled = dn < config_.normal_converge && int(p.obs.size()) >= config_.converge_min_observations;
    }
  }
  const int best = scoreObservations(p);
  if (best >= 0) p.reference = best;
  if (normal_settled) {
    // Converged: keep only the reference observation (and release the rest of the vector).
    std::vector<VisualObservation> keep(1, p.obs[std::size_t(p.reference)]);
    p.obs.swap(keep);
    p.reference = 0;
    p.converged = true;
  }
}

void VisualMap::reportPhotometricError(VisualPoint& p, double mean_sq_error, double gate) {
  if (mean_sq_error <= gate) {  // NaN counts as bad
    p.bad_updates = 0;
    return;
  }
  ++p.bad_updates;
  if (p.bad_updates == config_.max_bad_updates + 1) suspects_.push_back(p.id);
}

std::size_t VisualMap::removeBadPoints() {
  std::size_t removed = 0;
  for (const std::int64_t id : suspects_) {
    const VisualPoint* p = find(id);
    if (p != nullptr && p->bad_updates > config_.max_bad_updates && extract(id) != nullptr) ++removed;
  }
  suspects_.clear();
  return removed;
}

}  // namespace livo
