// The rotation search of ScanRegistration (scan_registration.hpp, method step 1): the scan's planar
// patches' normals against the map's normal density -- tilt from the normals' elevations, then yaw
// peaks -- so that a registration needs no rotation guess beyond its bounds. Internal to
// libs/estimation (scan_registration.cpp).
#pragma once

#include "livo/estimation/scan_registration.hpp"

#include <cmath>
#include <vector>

namespace livo::scan_detail {

inline Mat3 yawRotation(double yaw) { return Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix(); }

/// Density of unit normals (both signs) on a dense grid over [-1, 1]^3 with cells of `cell` (about
/// the angle in rad), blurred by a 3 x 3 x 3 box: a direction scores the weight of the normals within
/// about a cell of it.
class NormalDensity {
 public:
  explicit NormalDensity(double cell)
      : h_(cell), n_(static_cast<int>(std::ceil(2.0 / cell)) + 1), v_(static_cast<std::size_t>(n_) * n_ * n_, 0.0f) {}
  double cell() const { return h_; }
  void add(const Vec3& n, double w) {
    v_[index(n)] += static_cast<float>(w);
    v_[index(-n)] += static_cast<float>(w);
  }
  void blur() {
    std::vector<float> tmp(v_.size());
    const std::size_t stride[3] = {1, static_cast<std::size_t>(n_), static_cast<std::size_t>(n_) * n_};
    for (int axis = 0; axis < 3; ++axis) {
      for (int z = 0; z < n_; ++z)
        for (int y = 0; y < n_; ++y)
          for (int x = 0; x < n_; ++x) {
            const int c[3] = {x, y, z};
            const std::size_t i = x + stride[1] * y + stride[2] * z;
            float sum = v_[i];
            if (c[axis] > 0) sum += v_[i - stride[axis]];
            if (c[axis] + 1 < n_) sum += v_[i + stride[axis]];
            tmp[i] = sum;
          }
      v_.swap(tmp);
    }
  }
  double at(const Vec3& n) const { return v_[index(n)]; }

 private:
  int coord(double c) const { return std::clamp(static_cast<int>((c + 1.0) / h_), 0, n_ - 1); }
  std::size_t index(const Vec3& n) const {
    return static_cast<std::size_t>(coord(n.x())) + static_cast<std::size_t>(n_) * coord(n.y()) +
           static_cast<std::size_t>(n_) * n_ * coord(n.z());
  }
  double h_;
  int n_;
  std::vector<float> v_;
};

/// A rotation candidate: R = Rz(yaw) Exp([a, b, 0]) R0 (yaw about world z, tilt about world x and y).
struct RotCandidate {
  double yaw = 0.0, a = 0.0, b = 0.0;
  double score = -1.0;
};

inline Mat3 rotationOf(const RotCandidate& c, const Mat3& R0) { return yawRotation(c.yaw) * expSO3(Vec3(c.a, c.b, 0.0)) * R0; }

/// Histogram of the normals' elevation (angle to the horizontal plane, 0 to 90 deg, 1 deg bins,
/// blurred over +-2 bins): what a rotation about the vertical leaves unchanged.
class ElevationHistogram {
 public:
  ElevationHistogram() : v_(kBins, 0.0) {}
  void add(const Vec3& n, double w) { v_[bin(n)] += w; }
  void blur() {
    std::vector<double> out(kBins, 0.0);
    for (int i = 0; i < kBins; ++i)
      for (int j = std::max(0, i - 2); j <= std::min(kBins - 1, i + 2); ++j) out[i] += v_[j];
    v_.swap(out);
  }
  double at(const Vec3& n) const { return v_[bin(n)]; }

 private:
  static constexpr int kBins = 91;
  static int bin(const Vec3& n) {
    const double e = std::asin(std::min(1.0, std::abs(n.z()) / std::max(n.norm(), 1e-12))) * 180.0 / M_PI;
    return std::clamp(static_cast<int>(std::lround(e)), 0, kBins - 1);
  }
  std::vector<double> v_;
};

/// Rotation search over the normals (header, step 1). The tilt first, from the elevations alone (a
/// yaw does not change them): every (a, b) on a 2 deg grid within +-Tl, then +-1 deg around the best.
/// Then the yaw, every 1 deg within +-Y, at the best of the tilts within +-3 deg of that one, scored
/// against the map's normal density at 4 deg cells; its n_peaks best local maxima (at least 3 deg
/// apart) climb on the 2 deg density.
std::vector<RotCandidate> rotationSearch(const NormalDensity& fine, const NormalDensity& coarse,
                                         const ElevationHistogram& elev, const std::vector<NormalPatch>& patches,
                                         const Mat3& R0, double Y, double Tl, int n_peaks);

}  // namespace livo::scan_detail
