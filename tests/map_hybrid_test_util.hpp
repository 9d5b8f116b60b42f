// Shared scene builders for the hybrid-map tests (test_map_hybrid*.cpp, test_map_file.cpp).
#pragma once

#include "livo/map/hybrid_map.hpp"

#include <cmath>
#include <memory>
#include <random>
#include <vector>

namespace livo::test {

// Planar patch: every root voxel of edge `s` in [x0, x1) x [y0, y1) (at height z) gets `n` noisy
// points on the plane z = const, so that each root voxel holds one plane leaf (visible to forEachPlane).
inline void groundPatch(std::vector<PointWithCov>& out, double x0, double x1, double y0, double y1, double z, double s,
                 std::mt19937& rng, int n = 8) {
  std::uniform_real_distribution<double> u(0.05, 0.95);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (double x = std::floor(x0 / s) * s; x < x1 - 1e-9; x += s)
    for (double y = std::floor(y0 / s) * s; y < y1 - 1e-9; y += s)
      for (int i = 0; i < n; ++i) {
        PointWithCov p;
        p.p_world = Vec3(x + u(rng) * s, y + u(rng) * s, z + noise(rng));
        p.cov_world = Mat3::Identity() * 1e-4;
        out.push_back(p);
      }
}

// Same for a vertical wall y = y_wall, x in [x0, x1), z in [z0, z1).
inline void wallPatch(std::vector<PointWithCov>& out, double x0, double x1, double y_wall, double z0, double z1, double s,
               std::mt19937& rng, int n = 8) {
  std::uniform_real_distribution<double> u(0.05, 0.95);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (double x = std::floor(x0 / s) * s; x < x1 - 1e-9; x += s)
    for (double z = std::floor(z0 / s) * s; z < z1 - 1e-9; z += s)
      for (int i = 0; i < n; ++i) {
        PointWithCov p;
        p.p_world = Vec3(x + u(rng) * s, y_wall + noise(rng), z + u(rng) * s);
        p.cov_world = Mat3::Identity() * 1e-4;
        out.push_back(p);
      }
}

inline std::unique_ptr<VisualPoint> visualPoint(std::int64_t id, const Vec3& p, bool with_reference = true, int n_obs = 1) {
  auto vp = std::make_unique<VisualPoint>();
  vp->id = id;
  vp->p_world = p;
  vp->normal = Vec3(-1, 0, 0);
  if (with_reference) {
    for (int i = 0; i < n_obs; ++i) {
      vp->obs.emplace_back();
      vp->obs.back().utime = i;  // marks the observation
    }
    vp->reference = n_obs - 1;
    vp->views = n_obs;
  }
  return vp;
}

}  // namespace livo::test
