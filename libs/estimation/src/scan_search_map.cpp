// SearchMap and the scan's planar patches (scan_registration.hpp): what the registration's
// correlative and rotation searches look in, kept beside the voxel map.
#include "livo/estimation/scan_registration.hpp"

#include "livo/map/voxel_key.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace livo {

std::vector<NormalPatch> planarPatches(const std::vector<Vec3>& points, double cell, double max_eigen_value) {
  struct Acc {
    Vec3 origin = Vec3::Zero();  // the first point: sums relative to it stay exact far from the origin
    Vec3 s = Vec3::Zero();
    Mat3 ss = Mat3::Zero();
    int n = 0;
  };
  std::unordered_map<VoxelKey, Acc, VoxelKeyHash> cells;
  for (const Vec3& p : points) {
    if (!keyablePoint(p, cell)) continue;
    Acc& a = cells[VoxelKey::fromPoint(p, cell)];
    if (a.n == 0) a.origin = p;
    const Vec3 d = p - a.origin;
    a.s += d;
    a.ss.noalias() += d * d.transpose();
    ++a.n;
  }
  std::vector<NormalPatch> out;
  const double min_spread = std::pow(cell / 8.0, 2);
  for (const auto& kv : cells) {
    const Acc& a = kv.second;
    if (a.n < 6) continue;
    const Vec3 mean = a.s / a.n;
    const Mat3 C = a.ss / a.n - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Mat3> es(C);
    const Vec3 l = es.eigenvalues();
    if (!(l(0) < max_eigen_value) || !(l(1) > 4.0 * std::max(l(0), 0.0)) || !(l(1) > min_spread)) continue;
    out.push_back({es.eigenvectors().col(0).normalized(), a.origin + mean, double(a.n)});
  }
  return out;
}

namespace {
constexpr double kNormalKeyCell = M_PI / 180.0;  // 1 deg
}  // namespace

SearchMap::SearchMap(const ScanRegistrationConfig& cfg)
    : pyramid_(cfg.searchCell(), cfg.search_levels),
      voxel_m_(cfg.voxel_size_m),
      patch_eigen_(cfg.min_eigen_value + cfg.range_noise_m * cfg.range_noise_m),
      tile_m_(16.0 * cfg.voxel_size_m) {}

void SearchMap::clear() {
  pyramid_.clear();
  seen_.clear();
  normals_.clear();
}

void SearchMap::addNormal(const Vec3& position, const Vec3& normal, double weight) {
  if (!position.allFinite() || !normal.allFinite() || !(weight > 0) || !keyablePoint(position, tile_m_)) return;
  Vec3 n = normal.normalized();
  if (n.z() < 0 || (n.z() == 0 && (n.y() < 0 || (n.y() == 0 && n.x() < 0)))) n = -n;
  normals_[VoxelKey::fromPoint(position, tile_m_)][VoxelKey::fromPoint(n, kNormalKeyCell)] += weight;
}

void SearchMap::forEachNormal(const Vec3& center, double radius_m,
                              const std::function<void(const Vec3&, double)>& f) const {
  const double reach = radius_m + 0.87 * tile_m_;
  for (const auto& tile : normals_) {
    if ((tile.first.center(tile_m_) - center).norm() > reach) continue;
    for (const auto& kv : tile.second) f(kv.first.center(kNormalKeyCell).normalized(), kv.second);
  }
}

void SearchMap::addPoints(const std::vector<Vec3>& world) {
  // Points in one finest cell mark the same cells at every level (the cells nest): one per cell, ever.
  const double cell = pyramid_.cellSize(0);
  for (const Vec3& p : world)
    if (keyablePoint(p, cell) && seen_.insert(VoxelKey::fromPoint(p, cell)).second) pyramid_.insert(p);
  for (const NormalPatch& np : planarPatches(world, voxel_m_, patch_eigen_)) addNormal(np.center, np.normal, np.weight);
}

void SearchMap::addPlanes(const PlaneFinder& map, const Vec3& center, double radius_m) {
  const double h = pyramid_.cellSize(0);
  const double s = map.rootVoxelSize();
  const double gate = map.sigmaNum();
  std::vector<Vec3> samples;
  map.forEachPlane([&](const VoxelKey&, const Plane& pl) {
    if (!pl.is_plane) return;
    if (radius_m > 0 && (pl.center - center).norm() > radius_m) return;
    addNormal(pl.center, pl.normal, double(pl.num_points));
    // The plane's points lie in its octree cell (edge s / 2^layer) and within the association's
    // in-plane gate (sigma_num x radius) of its centre: sample the plane there.
    const double e = s / std::ldexp(1.0, pl.layer);
    const Vec3 lo = VoxelKey::fromPoint(pl.center, e).center(e) - Vec3::Constant(0.5 * e);
    const Vec3 hi = lo + Vec3::Constant(e);
    const Vec3 n = pl.normal.normalized();
    const Vec3 a = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
    const Vec3 b = n.cross(a);
    const double r = std::min(0.87 * e, gate * pl.radius);
    const int m = static_cast<int>(std::ceil(r / h));
    for (int i = -m; i <= m; ++i)
      for (int j = -m; j <= m; ++j) {
        const Vec3 q = pl.center + (i * h) * a + (j * h) * b;
        if ((q - pl.center).norm() > r) continue;
        if ((q.array() < lo.array() - 1e-9).any() || (q.array() > hi.array() + 1e-9).any()) continue;
        samples.push_back(q);
      }
  });
  for (const Vec3& p : samples)
    if (keyablePoint(p, h) && seen_.insert(VoxelKey::fromPoint(p, h)).second) pyramid_.insert(p);
}

}  // namespace livo
