#include "livo/map/occupancy_search.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace livo {

OccupancyPyramid::OccupancyPyramid(double finest_m, int levels) : finest_m_(finest_m) {
  if (!(finest_m > 0) || levels < 1 || levels > 12)
    throw std::invalid_argument("OccupancyPyramid: finest cell must be > 0 and levels in [1, 12]");
  levels_.resize(static_cast<std::size_t>(levels));
}

double OccupancyPyramid::cellSize(int level) const { return finest_m_ * std::ldexp(1.0, level); }

void OccupancyPyramid::insert(const Vec3& p) {
  if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 1e9) return;
  // Each point marks its cell and the 26 around it: two sweeps sample a surface at different spots
  // (a non-repeating pattern, a sparse LiDAR), so a query point counts when it lies within about a
  // cell of the map's points, not only in the very cell one of them fell in.
  for (std::size_t k = 0; k < levels_.size(); ++k) {
    const VoxelKey c = VoxelKey::fromPoint(p, cellSize(static_cast<int>(k)));
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int l = -1; l <= 1; ++l) levels_[k].insert({c.x + i, c.y + j, c.z + l});
  }
}

void OccupancyPyramid::clear() {
  for (auto& l : levels_) l = {};
}

int OccupancyPyramid::score(const std::vector<Vec3>& pts, const Vec3& t, int level, int at_least) const {
  const auto& cells = levels_[static_cast<std::size_t>(level)];
  const double s = cellSize(level);
  int n = 0;
  int left = static_cast<int>(pts.size());
  for (const auto& p : pts) {
    n += cells.count(VoxelKey::fromPoint(p + t, s)) ? 1 : 0;
    --left;
    if (n + left < at_least) break;
  }
  return n;
}

OccupancyPyramid::Result OccupancyPyramid::search(const std::vector<Vec3>& pts, const Vec3& center,
                                                  double radius_m) const {
  Result r;
  r.t = center;
  r.points = static_cast<int>(pts.size());
  if (pts.empty() || empty() || !center.allFinite() || !(radius_m >= 0)) return r;
  // The first level: the finest whose cell spans at least a sixth of the radius (at most 13 steps a
  // side), or the coarsest.
  const int top = static_cast<int>(levels_.size()) - 1;
  int level = 0;
  while (level < top && cellSize(level) * 6.0 < radius_m) ++level;
  int half = static_cast<int>(std::ceil(radius_m / cellSize(level)));
  Vec3 best = center;
  for (; level >= 0; --level) {
    const double step = cellSize(level);
    const Vec3 around = best;
    int best_hits = -1;
    double best_d = 0;
    for (int i = -half; i <= half; ++i)
      for (int j = -half; j <= half; ++j)
        for (int k = -half; k <= half; ++k) {
          const Vec3 t = around + Vec3(i, j, k) * step;
          if ((t - center).cwiseAbs().maxCoeff() > radius_m + 1e-9) continue;
          const int hits = score(pts, t, level);
          const double d = (t - center).squaredNorm();
          if (hits > best_hits || (hits == best_hits && d < best_d)) {
            best_hits = hits;
            best_d = d;
            best = t;
          }
        }
    r.hits = best_hits;
    half = 2;
  }
  r.t = best;
  return r;
}

}  // namespace livo
