#include "scan_rotation_search.hpp"

#include <algorithm>

namespace livo::scan_detail {

/// Rotation search over the normals (header, step 1). The tilt first, from the elevations alone (a
/// yaw does not change them): every (a, b) on a 2 deg grid within +-Tl, then +-1 deg around the best.
/// Then the yaw, every 1 deg within +-Y, at the best of the tilts within +-3 deg of that one, scored
/// against the map's normal density at 4 deg cells; its n_peaks best local maxima (at least 3 deg
/// apart) climb on the 2 deg density.
std::vector<RotCandidate> rotationSearch(const NormalDensity& fine, const NormalDensity& coarse,
                                         const ElevationHistogram& elev, const std::vector<NormalPatch>& patches,
                                         const Mat3& R0, double Y, double Tl, int n_peaks) {
  const double deg = M_PI / 180.0;
  RotCandidate tilt;
  if (Tl > 0) {
    auto tiltScore = [&](double a, double b) {
      const Mat3 R = expSO3(Vec3(a, b, 0.0)) * R0;
      double s = 0.0;
      for (const NormalPatch& p : patches) s += p.weight * elev.at(R * p.normal);
      return s;
    };
    auto consider = [&](double a, double b) {
      if (std::abs(a) > Tl + 1e-12 || std::abs(b) > Tl + 1e-12) return;
      const double s = tiltScore(a, b);
      if (s > tilt.score || (s == tilt.score && a * a + b * b < tilt.a * tilt.a + tilt.b * tilt.b)) {
        tilt.score = s;
        tilt.a = a;
        tilt.b = b;
      }
    };
    const int n = static_cast<int>(std::floor(Tl / (2 * deg)));
    for (int i = -n; i <= n; ++i)
      for (int j = -n; j <= n; ++j) consider(i * 2 * deg, j * 2 * deg);
    const RotCandidate coarse = tilt;
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j) consider(coarse.a + i * deg, coarse.b + j * deg);
  }
  const int ny = static_cast<int>(std::floor(Y / deg));
  std::vector<RotCandidate> profile;
  // The elevations settle the tilt within a few degrees only: each yaw takes the best of the tilts
  // within +-3 deg of theirs.
  for (int i = -ny; i <= ny; ++i) {
    RotCandidate best;
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k) {
        if (Tl <= 0 && (j || k)) continue;
        RotCandidate c = tilt;
        c.yaw = i * deg;
        c.a = std::clamp(tilt.a + j * 3 * deg, -Tl, Tl);
        c.b = std::clamp(tilt.b + k * 3 * deg, -Tl, Tl);
        const Mat3 R = rotationOf(c, R0);
        double s = 0.0;
        for (const NormalPatch& p : patches) s += p.weight * coarse.at(R * p.normal);
        c.score = s;
        if (c.score > best.score) best = c;
      }
    profile.push_back(best);
  }
  // Local maxima of the yaw profile (ties to the smaller yaw offset), at least 4 deg apart.
  std::vector<RotCandidate> peaks;
  for (std::size_t i = 0; i < profile.size(); ++i) {
    bool peak = true;
    for (std::size_t j = (i >= 2 ? i - 2 : 0); j <= std::min(profile.size() - 1, i + 2); ++j)
      if (j != i && (profile[j].score > profile[i].score ||
                     (profile[j].score == profile[i].score && std::abs(profile[j].yaw) < std::abs(profile[i].yaw))))
        peak = false;
    if (peak) peaks.push_back(profile[i]);
  }
  auto better = [](const RotCandidate& x, const RotCandidate& y) {
    return x.score > y.score || (x.score == y.score && std::abs(x.yaw) < std::abs(y.yaw));
  };
  std::sort(peaks.begin(), peaks.end(), better);
  if (peaks.size() > static_cast<std::size_t>(n_peaks)) peaks.resize(static_cast<std::size_t>(n_peaks));
  // Each peak climbs jointly in (yaw, a, b) on the fine density, 1 deg steps, within the bounds (the
  // tilt from the elevations alone may be a few degrees off: the wall normals settle it).
  auto fineScore = [&](RotCandidate& c) {
    const Mat3 R = rotationOf(c, R0);
    double s = 0.0;
    for (const NormalPatch& p : patches) s += p.weight * fine.at(R * p.normal);
    c.score = s;
  };
  for (RotCandidate& c : peaks) {
    fineScore(c);
    for (int it = 0; it < 12; ++it) {
      RotCandidate best = c;
      for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
          for (int k = -1; k <= 1; ++k) {
            if ((!i && !j && !k) || (Y <= 0 && i) || (Tl <= 0 && (j || k))) continue;
            RotCandidate n = c;
            n.yaw += i * deg;
            n.a += j * deg;
            n.b += k * deg;
            if (std::abs(n.yaw) > Y + 1e-12 || std::abs(n.a) > Tl + 1e-12 || std::abs(n.b) > Tl + 1e-12) continue;
            fineScore(n);
            if (n.score > best.score) best = n;
          }
      if (best.score <= c.score) break;
      c = best;
    }
  }
  std::sort(peaks.begin(), peaks.end(), better);
  // Peaks that climbed onto one another: one of them.
  std::vector<RotCandidate> out;
  for (const RotCandidate& c : peaks) {
    bool dup = false;
    for (const RotCandidate& o : out)
      if (std::abs(c.yaw - o.yaw) < 2 * deg && std::abs(c.a - o.a) < 2 * deg && std::abs(c.b - o.b) < 2 * deg) dup = true;
    if (!dup) out.push_back(c);
  }
  return out;
}

}  // namespace livo::scan_detail
