#include "scan_correlative_search.hpp"

#include "scan_rotation_search.hpp"

#include "livo/map/voxel_key.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace livo::scan_detail {

/// Indices of `pts` thinned to one per cube of `cell` (the first in scan order), then strided down to
/// at most `max_n`.
std::vector<std::size_t> spread(const std::vector<BodyPoint>& pts, double cell, int max_n) {
  std::unordered_set<VoxelKey, VoxelKeyHash> seen;
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (keyablePoint(pts[i].p_imu, cell) && seen.insert(VoxelKey::fromPoint(pts[i].p_imu, cell)).second)
      idx.push_back(i);
  if (max_n > 0 && idx.size() > static_cast<std::size_t>(max_n)) {
    std::vector<std::size_t> out;
    out.reserve(static_cast<std::size_t>(max_n));
    const double stride = double(idx.size()) / max_n;
    for (int k = 0; k < max_n; ++k) out.push_back(idx[static_cast<std::size_t>(k * stride)]);
    idx.swap(out);
  }
  return idx;
}

bool better(const Candidate& a, const Candidate& b) {
  return a.score > b.score || (a.score == b.score && a.tie < b.tie);
}

/// The correlative search (header, step 1). Returns the candidates of the finest level, best first.
/// Candidates that cannot reach `floor_score` are not counted to the end (a coarser level's score is
/// at least the finer one's: a rotation whose best cannot reach it is given up early).
std::vector<Candidate> correlativeSearch(const OccupancyPyramid& pyr, const std::vector<Vec3>& pts_body,
                                         const Pose& T0, const SearchBounds& b, int beam, double& yaw_step0,
                                         int floor_score) {
  const Mat3 R0 = T0.linear();
  const Vec3 p0 = T0.translation();
  // Reference horizontal range: the 75th percentile of the scored points' distance from the z axis
  // (after R0); a yaw step of cell / range moves such a point by one cell.
  std::vector<double> ranges;
  for (const Vec3& p : pts_body) ranges.push_back((R0 * p).head<2>().norm());
  std::nth_element(ranges.begin(), ranges.begin() + ranges.size() * 3 / 4, ranges.end());
  const double r_ref = std::max(1.0, ranges[ranges.size() * 3 / 4]);
  auto yawStep = [&](int level) { return pyr.cellSize(level) / r_ref; };

  const double R = std::max(0.0, b.translation_m);
  const double Y = std::max(0.0, b.yaw_rad);
  const int top = pyr.levels() - 1;
  int level = 0;
  // Translation alone: every translation of the finest level whose cell is at least a third of the
  // radius (at most 7 a side). With yaw: the finest level whose cell is at least half the radius and
  // whose yaw step leaves at most 8 steps either side.
  if (Y > 0) {
    while (level < top && (pyr.cellSize(level) * 2.0 < R || Y / yawStep(level) > 8.0)) ++level;
  } else {
    while (level < top && pyr.cellSize(level) * 3.0 < R) ++level;
  }
  yaw_step0 = yawStep(0);

  // The scores of the best `n` candidates so far: a candidate that cannot reach the n-th is not
  // counted to the end (OccupancyPyramid::score's at_least).
  struct Bar {
    std::size_t n;
    std::vector<int> top;  // ascending, at most n
    int atLeast() const { return top.size() < n ? 0 : top.front(); }
    void add(int s) {
      if (top.size() < n) {
        top.insert(std::upper_bound(top.begin(), top.end(), s), s);
      } else if (s > top.front()) {
        top.erase(top.begin());
        top.insert(std::upper_bound(top.begin(), top.end(), s), s);
      }
    }
  };
  auto score = [&](Candidate& c, int lvl, std::vector<Vec3>& rotated, int at_least) {
    const Mat3 Rc = yawRotation(c.yaw) * R0;
    rotated.resize(pts_body.size());
    for (std::size_t i = 0; i < pts_body.size(); ++i) rotated[i] = Rc * pts_body[i];
    c.score = pyr.score(rotated, p0 + c.t, lvl, at_least);
    c.tie = (c.t / pyr.cellSize(0)).squaredNorm() + std::pow(c.yaw / yaw_step0, 2);
  };
  auto inside = [&](const Candidate& c) {
    return c.t.cwiseAbs().maxCoeff() <= R + 1e-9 && std::abs(c.yaw) <= Y + 1e-12;
  };

  // Top level: every translation of the level's grid x every yaw of its step.
  std::vector<Candidate> cands;
  {
    Bar bar{static_cast<std::size_t>(beam), {}};
    const double cell = pyr.cellSize(level);
    const int half = R > 0 ? static_cast<int>(std::ceil(R / cell)) : 0;
    const double ystep = yawStep(level);
    const int yhalf = Y > 0 ? static_cast<int>(std::ceil(Y / ystep)) : 0;
    std::vector<Vec3> rotated(pts_body.size());
    for (int y = -yhalf; y <= yhalf; ++y) {
      const double yaw = std::clamp(y * ystep, -Y, Y);
      const Mat3 Rc = yawRotation(yaw) * R0;
      for (std::size_t i = 0; i < pts_body.size(); ++i) rotated[i] = Rc * pts_body[i];
      for (int i = -half; i <= half; ++i)
        for (int j = -half; j <= half; ++j)
          for (int k = -half; k <= half; ++k) {
            Candidate c;
            c.yaw = yaw;
            c.t = Vec3(i, j, k) * cell;
            c.t = c.t.cwiseMax(Vec3::Constant(-R)).cwiseMin(Vec3::Constant(R));
            c.score = pyr.score(rotated, p0 + c.t, level, std::max(floor_score, bar.atLeast()));
            c.tie = (c.t / pyr.cellSize(0)).squaredNorm() + std::pow(c.yaw / yaw_step0, 2);
            bar.add(c.score);
            cands.push_back(c);
          }
    }
  }
  auto keepBest = [&](std::vector<Candidate>& v, std::size_t n) {
    std::sort(v.begin(), v.end(), better);
    // Drop duplicates (the same candidate reached from two beam members).
    std::vector<Candidate> out;
    for (const Candidate& c : v) {
      bool dup = false;
      for (const Candidate& o : out)
        if ((o.t - c.t).cwiseAbs().maxCoeff() < 1e-9 && std::abs(o.yaw - c.yaw) < 1e-12) {
          dup = true;
          break;
        }
      if (!dup) out.push_back(c);
      if (out.size() >= n) break;
    }
    v.swap(out);
  };
  keepBest(cands, static_cast<std::size_t>(beam));

  // Finer levels: each kept candidate's 3 yaws x 27 translations at the level's steps.
  std::vector<Vec3> rotated;
  while (level > 0) {
    --level;
    const double cell = pyr.cellSize(level);
    const double ystep = Y > 0 ? yawStep(level) : 0.0;
    std::vector<Candidate> next;
    Bar bar{static_cast<std::size_t>(beam), {}};
    for (const Candidate& c : cands)
      for (int y = -1; y <= 1; ++y) {
        if (Y <= 0 && y != 0) continue;
        for (int i = -1; i <= 1; ++i)
          for (int j = -1; j <= 1; ++j)
            for (int k = -1; k <= 1; ++k) {
              if (R <= 0 && (i || j || k)) continue;
              Candidate n;
              n.yaw = c.yaw + y * ystep;
              n.t = c.t + Vec3(i, j, k) * cell;
              if (!inside(n)) continue;
              // At the finest level every candidate within kAmbiguousScore of the best so far is
              // counted to the end (hypotheses near the best); above it the beam's last.
              const int at_least = std::max(
                  floor_score, level == 0 ? static_cast<int>(std::floor(ScanRegistration::kAmbiguousScore *
                                                                        (bar.top.empty() ? 0 : bar.top.back())))
                                          : bar.atLeast());
              score(n, level, rotated, at_least);
              bar.add(n.score);
              next.push_back(n);
            }
      }
    // Keep the whole scored set of the finest level (distinct() picks the hypotheses from it).
    keepBest(next, level == 0 ? next.size() : static_cast<std::size_t>(beam));
    cands.swap(next);
  }
  return cands;
}

/// The distinct candidates to refine, best first (at most n; the next must be away from the kept).
std::vector<Candidate> distinct(const std::vector<Candidate>& cands, int n, double cell0, double yaw_step0) {
  std::vector<Candidate> out;
  for (const Candidate& c : cands) {
    bool near = false;
    for (const Candidate& o : out)
      if ((c.t - o.t).cwiseAbs().maxCoeff() <= 2.0 * cell0 + 1e-9 && std::abs(c.yaw - o.yaw) <= 2.0 * yaw_step0 + 1e-12)
        near = true;
    if (!near) out.push_back(c);
    if (static_cast<int>(out.size()) >= n) break;
  }
  return out;
}

}  // namespace livo::scan_detail
