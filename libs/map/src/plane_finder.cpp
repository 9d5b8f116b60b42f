#include "livo/map/plane_finder.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace livo {
namespace {
// |p / s| below 2^52 keeps floor() exact and the key far from int64 overflow.
constexpr double kMaxScaled = 4503599627370496.0;
}  // namespace

bool keyablePoint(const Vec3& p, double voxel_size) {
  return p.allFinite() && (p.cwiseAbs() / voxel_size).maxCoeff() < kMaxScaled;
}

bool scorePlaneCandidate(const Plane& plane, const PointWithCov& pw, double sigma_num, bool have_best,
                         PlaneMatch& best) {
  const Vec3& p = pw.p_world;
  const double dist = plane.signedDistance(p);
  // In-plane distance gate: sqrt(|p - q|^2 - d^2) <= sigma_num * sqrt(lambda_max).
  const double in_plane_sq = std::max((p - plane.center).squaredNorm() - dist * dist, 0.0);
  const double r_gate = sigma_num * plane.radius;
  if (in_plane_sq > r_gate * r_gate) return false;
  const double sigma_l = pointToPlaneVariance(plane, p, pw.cov_world);
  if (!(sigma_l > 0.0)) return false;
  if (dist * dist >= sigma_num * sigma_num * sigma_l) return false;  // |d| < sigma_num sqrt(sigma_l)
  const double prob = std::exp(-0.5 * dist * dist / sigma_l) / std::sqrt(sigma_l);
  if (have_best && prob <= best.probability) return false;
  best.plane = &plane;
  best.distance = dist;
  best.sigma_l = sigma_l;
  best.probability = prob;
  return true;
}

bool neighbourVoxelKey(const Vec3& p, double voxel_size, VoxelKey& out) {
  // Position inside the voxel in units of the voxel edge, in [0, 1): metric, not index, coordinates
  // (FAST-LIVO2 mixes the two, docs/algorithms.md section 2 [quirk]).
  const Vec3 scaled = p / voxel_size;
  const Vec3 fl(std::floor(scaled.x()), std::floor(scaled.y()), std::floor(scaled.z()));
  const Vec3 frac = scaled - fl;
  out = VoxelKey::fromPoint(p, voxel_size);
  bool any = false;
  std::int64_t* k[3] = {&out.x, &out.y, &out.z};
  for (int i = 0; i < 3; ++i) {
    if (frac[i] > 0.75) {
      ++*k[i];
      any = true;
    } else if (frac[i] < 0.25) {
      --*k[i];
      any = true;
    }
  }
  return any;
}

PlaneIndex::PlaneIndex(double voxel_size_m, double sigma_num) : voxel_size_(voxel_size_m), sigma_num_(sigma_num) {
  if (!(voxel_size_m > 0.0) || !std::isfinite(voxel_size_m))
    throw std::invalid_argument("PlaneIndex: voxel_size_m must be finite and > 0");
  if (!(sigma_num > 0.0) || !std::isfinite(sigma_num))
    throw std::invalid_argument("PlaneIndex: sigma_num must be finite and > 0");
}

void PlaneIndex::add(const VoxelKey& key, const Plane& plane) {
  voxels_[key].push_back(plane);
  ++planes_;
}

void PlaneIndex::clear() {
  voxels_.clear();
  planes_ = 0;
}

void PlaneIndex::reset(double voxel_size_m) {
  if (!(voxel_size_m > 0.0) || !std::isfinite(voxel_size_m))
    throw std::invalid_argument("PlaneIndex: voxel_size_m must be finite and > 0");
  clear();
  voxel_size_ = voxel_size_m;
}

void PlaneIndex::visitPlanes(const VoxelKey& key, const std::function<void(const Plane&)>& f) const {
  const auto it = voxels_.find(key);
  if (it == voxels_.end()) return;
  for (const Plane& plane : it->second) f(plane);
}

void PlaneIndex::forEachPlane(const std::function<void(const VoxelKey&, const Plane&)>& f) const {
  for (const auto& [key, planes] : voxels_)
    for (const Plane& plane : planes) f(key, plane);
}

void CachedAssociation::Candidates::fetch(const PlaneFinder& finder, const VoxelKey& key) {
  n = 0;
  finder.visitPlanes(key, [&](const Plane& plane) {
    if (n < kMaxCached) planes[std::size_t(n)] = &plane;
    n = std::min(n + 1, kMaxCached + 1);
  });
}

bool CachedAssociation::Candidates::best(const PlaneFinder& finder, const VoxelKey& key, const PointWithCov& pw,
                                         PlaneMatch& out) const {
  bool found = false;
  const double sigma_num = finder.sigmaNum();
  if (n > kMaxCached) {
    finder.visitPlanes(key, [&](const Plane& plane) {
      if (scorePlaneCandidate(plane, pw, sigma_num, found, out)) found = true;
    });
    return found;
  }
  for (int i = 0; i < n; ++i)
    if (scorePlaneCandidate(*planes[std::size_t(i)], pw, sigma_num, found, out)) found = true;
  return found;
}

bool CachedAssociation::find(const PlaneFinder& finder, const PointWithCov& pw, PlaneMatch& out) {
  out = PlaneMatch{};
  const double s = finder.rootVoxelSize();
  if (!keyablePoint(pw.p_world, s)) return false;
  const VoxelKey own = VoxelKey::fromPoint(pw.p_world, s);
  if (own_.n < 0 || !(own == own_key_)) {
    own_key_ = own;
    own_.fetch(finder, own);
    near_.n = -1;  // the neighbour depends on the voxel
  }
  if (own_.best(finder, own_key_, pw, out)) return true;
  out = PlaneMatch{};
  VoxelKey near;
  const bool has_near = neighbourVoxelKey(pw.p_world, s, near);
  if (!has_near) return false;
  if (near_.n < 0 || !has_near_ || !(near == near_key_)) {
    near_key_ = near;
    near_.fetch(finder, near);
  }
  has_near_ = true;
  return near_.best(finder, near_key_, pw, out);
}

bool PlaneFinder::findBestPlane(const PointWithCov& pw, PlaneMatch& out) const {
  CachedAssociation one_shot;
  return one_shot.find(*this, pw, out);
}

}  // namespace livo
