#include "livo/estimation/vio_update.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace livo {

void VioConfig::load(const ConfigNode& root) {
  if (root.has("camera")) root.section("camera").get("pixel_noise", pixel_noise);
  const ConfigNode n = root.section("vio");
  n.get("max_iterations", max_iterations).get("outlier_rms", outlier_rms);
  n.get("estimate_exposure", estimate_exposure).get("normal_warp", normal_warp);
  n.get("converge_rot_deg", converge_rot_deg).get("converge_pos_m", converge_pos_m).get("model_noise", model_noise);
  n.check(model_noise >= 0, "model_noise", "must be >= 0");
  n.check(max_iterations >= 1 && max_iterations <= 50, "max_iterations", "must be in 1..50");
  n.check(outlier_rms > 0, "outlier_rms", "must be > 0");
  n.check(pixel_noise > 0, "pixel_noise", "must be > 0");
}

namespace {

using Row7 = Eigen::Matrix<double, 1, 7>;
using Mat7 = Eigen::Matrix<double, 7, 7>;
using Vec7 = Eigen::Matrix<double, 7, 1>;

constexpr int kN = PatchPyramid::kSize;
constexpr int kL = PatchPyramid::kLevels;

struct PointState {
  const VisualPoint* point = nullptr;
  const VisualObservation* ref = nullptr;
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();  // d px_ref / d px_cur
  bool used = false;
  /// tau_ref * P_ref at every patch pixel of every level, warped by A: fixed during the update, so
  /// sampled once (NaN: outside the reference crop).
  std::array<double, std::size_t(kL * kN * kN)> ref_values{};
  double refValue(int level, int row, int col) const { return ref_values[std::size_t((level * kN + row) * kN + col)]; }
};

/// Samples the reference patch of `ps` through its warp at every pixel of every level.
void precomputeReference(PointState& ps) {
  for (int level = 0; level < kL; ++level)
    for (int row = 0; row < kN; ++row)
      for (int col = 0; col < kN; ++col) {
        const Vec2 d_ref = ps.A * Vec2(patchOffset(col), patchOffset(row));
        float P_ref = 0;
        ps.ref_values[std::size_t((level * kN + row) * kN + col)] =
            ps.ref->patch.sample(level, d_ref.x(), d_ref.y(), P_ref) ? double(ps.ref->inv_exposure) * P_ref
                                                                     : std::numeric_limits<double>::quiet_NaN();
      }
}

struct Linearization {
  Mat7 HtRH = Mat7::Zero();
  Vec7 HtRz = Vec7::Zero();
  double cost = 0.0;
  std::size_t n = 0;
};

bool projectPoint(const NavState& x, const Pose& T_imu_camera, const CameraModel& cam, const Vec3& p_w, Vec3& p_i,
                  Vec3& p_c, Vec2& px, Eigen::Matrix<double, 2, 3>* J) {
  p_i = x.R_world_imu.transpose() * (p_w - x.p_world_imu);
  p_c = T_imu_camera.linear().transpose() * (p_i - T_imu_camera.translation());
  return cam.project(p_c, px, J);
}

}  // namespace

Eigen::Matrix2d warpRefFromCur(const VisualPoint& p, const VisualObservation& ref, const Pose& T_world_camera,
                               const CameraModel& cam) {
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  Vec2 px_cur;
  if (!cam.project(T_world_camera.inverse() * p.p_world, px_cur)) return A;
  const Pose T_ref_world = ref.T_world_camera.inverse();
  const Vec3 c = T_world_camera.translation();
  const double h = 2.0;  // pixels
  for (int axis = 0; axis < 2; ++axis) {
    Vec2 px_ref[2];
    for (int s = 0; s < 2; ++s) {
      Vec2 q = px_cur;
      q[axis] += s == 0 ? h : -h;
      Vec3 bearing;
      if (!cam.unproject(q, bearing)) return Eigen::Matrix2d::Identity();
      const Vec3 dir = T_world_camera.linear() * bearing;
      const double denom = p.normal.dot(dir);
      if (std::abs(denom) < 1e-3) return Eigen::Matrix2d::Identity();  // plane seen edge-on
      const double t = p.normal.dot(p.p_world - c) / denom;
      if (!(t > 0)) return Eigen::Matrix2d::Identity();
      if (!cam.project(T_ref_world * (c + t * dir), px_ref[s])) return Eigen::Matrix2d::Identity();
    }
    A.col(axis) = (px_ref[0] - px_ref[1]) / (2 * h);
  }
  if (!A.allFinite() || std::abs(A.determinant()) < 1e-3) return Eigen::Matrix2d::Identity();
  return A;
}

namespace {

/// The point's projection at state x, shared by all pixels of its patch: computed once per point and
/// linearisation instead of once per pixel.
struct PointProjection {
  Vec3 p_i = Vec3::Zero();
  Vec2 px = Vec2::Zero();
  Eigen::Matrix<double, 2, 3> J_theta = Eigen::Matrix<double, 2, 3>::Zero();  // d px / d dtheta
  Eigen::Matrix<double, 2, 3> J_pos = Eigen::Matrix<double, 2, 3>::Zero();    // d px / d dp
};

bool projectForPatch(const NavState& x, const Pose& T_imu_camera, const CameraModel& cam, const Vec3& p_w,
                     bool with_jacobian, PointProjection& out) {
  Vec3 p_c;
  Eigen::Matrix<double, 2, 3> J;
  if (!projectPoint(x, T_imu_camera, cam, p_w, out.p_i, p_c, out.px, with_jacobian ? &J : nullptr)) return false;
  if (with_jacobian) {
    const Mat3 R_ci = T_imu_camera.linear().transpose();
    out.J_theta = J * R_ci * hat(out.p_i);                          // p_i -> p_i + [p_i]x dtheta
    out.J_pos = -J * R_ci * x.R_world_imu.transpose();              // p_i -> p_i - R^T dp
  }
  return true;
}

/// Residual of one patch pixel given the point's projection (see photometricResidual).
bool pixelResidual(const NavState& x, const Image& gray, const VisualObservation& ref, const Eigen::Matrix2d& A,
                   const PointProjection& pp, int level, int row, int col, bool with_jacobian, double& r,
                   Eigen::Matrix<double, 1, 7>* H) {
  const double stride = double(1 << level);
  const Vec2 o(patchOffset(col), patchOffset(row));  // level units
  const Vec2 u = pp.px + o * stride;
  float I = 0, P_ref = 0;
  const Vec2 d_ref = A * o;  // the same displacement in the reference, level units
  if (!ref.patch.sample(level, d_ref.x(), d_ref.y(), P_ref)) return false;
  if (!sampleBilinear(gray, u.x(), u.y(), I)) return false;
  r = x.inv_exposure * I - double(ref.inv_exposure) * P_ref;
  if (with_jacobian) {
    float Ixp = 0, Ixm = 0, Iyp = 0, Iym = 0;
    if (!sampleBilinear(gray, u.x() + stride, u.y(), Ixp) || !sampleBilinear(gray, u.x() - stride, u.y(), Ixm) ||
        !sampleBilinear(gray, u.x(), u.y() + stride, Iyp) || !sampleBilinear(gray, u.x(), u.y() - stride, Iym))
      return false;
    const Eigen::RowVector2d g = x.inv_exposure * Eigen::RowVector2d((Ixp - Ixm) / (2 * stride), (Iyp - Iym) / (2 * stride));
    H->segment<3>(0) = g * pp.J_theta;
    H->segment<3>(3) = g * pp.J_pos;
    (*H)(6) = I;
  }
  return true;
}

}  // namespace

bool photometricResidual(const NavState& x, const Image& gray, const CameraModel& cam, const Pose& T_imu_camera,
                         const VisualPoint& p, const Eigen::Matrix2d& A, int level, int row, int col, double& r,
                         Row7* H) {
  const VisualObservation* ref = p.referenceObs();
  if (!ref) return false;
  PointProjection pp;
  if (!projectForPatch(x, T_imu_camera, cam, p.p_world, H != nullptr, pp)) return false;
  return pixelResidual(x, gray, *ref, A, pp, level, row, col, H != nullptr, r, H);
}

namespace {

/// The current image around a point's pixel at one level, sampled once: the patch pixels and a ring of
/// one sample around them (the central differences' neighbours), at px + (i - (kN - 1) / 2) stride for
/// i = -1 .. kN. NaN where a sample falls outside the image.
struct CurrentGrid {
  static constexpr int kG = kN + 2;
  std::array<float, std::size_t(kG * kG)> v{};
  float at(int gi, int gj) const { return v[std::size_t(gi * kG + gj)]; }  // row, column of the grid

  void sample(const Image& gray, const Vec2& px, int level) {
    const double stride = double(1 << level);
    double xs[kG], ys[kG];
    for (int g = 0; g < kG; ++g) {
      xs[g] = px.x() + patchOffset(g - 1) * stride;
      ys[g] = px.y() + patchOffset(g - 1) * stride;
    }
    sampleBilinearGrid(gray, xs, kG, ys, kG, v.data());
  }
};

/// RMS of a point's patch residuals at one level; -1 when fewer than half the samples are usable.
double pointRms(const NavState& x, const Image& gray, const CameraModel& cam, const Pose& T_ic, const PointState& ps,
                int level) {
  PointProjection pp;
  if (!projectForPatch(x, T_ic, cam, ps.point->p_world, false, pp)) return -1.0;
  CurrentGrid grid;
  grid.sample(gray, pp.px, level);
  double sq = 0;
  int n = 0;
  for (int row = 0; row < kN; ++row)
    for (int col = 0; col < kN; ++col) {
      const double P = ps.refValue(level, row, col);
      const float I = grid.at(row + 1, col + 1);
      if (std::isnan(P) || std::isnan(I)) continue;
      const double r = x.inv_exposure * I - P;
      sq += r * r;
      ++n;
    }
  return n >= kN * kN / 2 ? std::sqrt(sq / n) : -1.0;
}

/// Sums of one point's patch over its usable pixels: with g = tau d I / d px (1 x 2) and the pixel's
/// row H = [g J, I] (J = d px / d [dtheta, dp], the same for every pixel of the patch), H^T H and
/// H^T r follow from the moments of g, I and r, so each pixel costs a few products instead of a 7 x 7
/// outer product.
struct PatchMoments {
  Eigen::Matrix2d gg = Eigen::Matrix2d::Zero();  // sum g^T g
  Vec2 gI = Vec2::Zero(), gr = Vec2::Zero();     // sum g^T I, sum g^T r
  double II = 0, Ir = 0, rr = 0;
  std::size_t n = 0;
};

PatchMoments patchMoments(const NavState& x, const CurrentGrid& grid, const PointState& ps, int level) {
  const double inv2s = 1.0 / (2.0 * double(1 << level));
  PatchMoments m;
  for (int row = 0; row < kN; ++row)
    for (int col = 0; col < kN; ++col) {
      const double P = ps.refValue(level, row, col);
      const float I = grid.at(row + 1, col + 1);
      const float Ixp = grid.at(row + 1, col + 2), Ixm = grid.at(row + 1, col);
      const float Iyp = grid.at(row + 2, col + 1), Iym = grid.at(row, col + 1);
      if (std::isnan(P) || std::isnan(I) || std::isnan(Ixp) || std::isnan(Ixm) || std::isnan(Iyp) || std::isnan(Iym))
        continue;
      const double r = x.inv_exposure * I - P;
      const Vec2 g = x.inv_exposure * Vec2((Ixp - Ixm) * inv2s, (Iyp - Iym) * inv2s);
      m.gg.noalias() += g * g.transpose();
      m.gI += g * double(I);
      m.gr += g * r;
      m.II += double(I) * I;
      m.Ir += double(I) * r;
      m.rr += r * r;
      ++m.n;
    }
  return m;
}

/// Points per block of the per-point loops: fixed, so that partial sums (and the update) are the same
/// for every thread count.
constexpr std::size_t kPointBlock = 8;

/// Adds points [begin, end) of `pts` to `lin`.
void linearizeBlock(const NavState& x, const Image& gray, const CameraModel& cam, const Pose& T_ic,
                    const std::vector<PointState>& pts, std::size_t begin, std::size_t end, int level, double inv_var,
                    bool exposure, Linearization& out) {
  Linearization lin;  // local, stored once at the end: no cache line shared with a neighbour block meanwhile
  CurrentGrid grid;
  for (std::size_t i = begin; i < end; ++i) {
    const PointState& ps = pts[i];
    if (!ps.used) continue;
    PointProjection pp;
    if (!projectForPatch(x, T_ic, cam, ps.point->p_world, true, pp)) continue;
    grid.sample(gray, pp.px, level);
    const PatchMoments m = patchMoments(x, grid, ps, level);
    if (m.n == 0) continue;
    Eigen::Matrix<double, 2, 6> J;
    J << pp.J_theta, pp.J_pos;
    lin.HtRH.topLeftCorner<6, 6>().noalias() += inv_var * (J.transpose() * m.gg * J);
    lin.HtRz.head<6>().noalias() += inv_var * (J.transpose() * m.gr);
    if (exposure) {
      const Eigen::Matrix<double, 6, 1> c = inv_var * (J.transpose() * m.gI);
      lin.HtRH.block<6, 1>(0, 6) += c;
      lin.HtRH.block<1, 6>(6, 0) += c.transpose();
      lin.HtRH(6, 6) += inv_var * m.II;
      lin.HtRz(6) += inv_var * m.Ir;
    }
    lin.cost += m.rr;
    lin.n += m.n;
  }
  out = lin;
}

/// Normal equations of every used point at level `level`: blocks of points in parallel on `pool`,
/// summed in block order.
Linearization linearize(const NavState& x, const Image& gray, const CameraModel& cam, const Pose& T_ic,
                        const std::vector<PointState>& pts, int level, double inv_var, bool exposure,
                        WorkerPool* pool) {
  std::vector<Linearization> blocks((pts.size() + kPointBlock - 1) / kPointBlock);
  forRange(pool, pts.size(), kPointBlock, [&](std::size_t begin, std::size_t end) {
    linearizeBlock(x, gray, cam, T_ic, pts, begin, end, level, inv_var, exposure, blocks[begin / kPointBlock]);
  });
  Linearization lin;
  for (const Linearization& b : blocks) {
    lin.HtRH += b.HtRH;
    lin.HtRz += b.HtRz;
    lin.cost += b.cost;
    lin.n += b.n;
  }
  return lin;
}

/// Step 1. Per point: warp from the plane normal and the outlier gate at level 0 at the prior.
/// Returns the squared RMS summed over the points used.
double gatePoints(const NavState& x, const Image& gray, const CameraModel& cam, const Pose& T_imu_camera,
                  const std::vector<VisualPoint*>& points, const VioConfig& cfg, std::vector<PointState>& pts,
                  VioUpdateResult& res, WorkerPool* pool) {
  const Pose T_world_camera = x.pose() * T_imu_camera;
  pts.assign(points.size(), PointState{});
  std::vector<double> rms(points.size(), -1.0);
  forRange(pool, points.size(), kPointBlock, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      PointState& ps = pts[i];
      ps.point = points[i];
      ps.ref = points[i] ? points[i]->referenceObs() : nullptr;
      if (!ps.ref) continue;
      if (cfg.normal_warp) ps.A = warpRefFromCur(*ps.point, *ps.ref, T_world_camera, cam);
      precomputeReference(ps);
      rms[i] = pointRms(x, gray, cam, T_imu_camera, ps, 0);
      ps.used = rms[i] >= 0 && rms[i] <= cfg.outlier_rms;
    }
  });
  double sq = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const PointState& ps = pts[i];
    if (ps.used) {
      ++res.points_used;
      sq += rms[i] * rms[i];
    } else {
      ++res.points_rejected;
    }
  }
  return sq;
}

/// Step 2. Coarse to fine: iterated updates per level, information form over [dtheta, dp, dtau] (the
/// first 7 error-state entries), rolling back an iteration that raises the mean squared error.
/// Returns false when no iteration linearised anything (P stays the prior); else `K_bar` is the
/// posterior covariance of the last linearisation.
bool iterateLevels(NavState& x, const StateCov& P_prop, const Image& gray, const CameraModel& cam,
                   const Pose& T_imu_camera, const std::vector<PointState>& pts, const VioConfig& cfg,
                   StateCov& K_bar, VioUpdateResult& res, WorkerPool* pool) {
  const NavState x_prop = x;
  const double inv_var = 1.0 / cfg.residualVariance();
  const StateCov P_prop_inv = P_prop.ldlt().solve(StateCov::Identity());
  bool have_K = false;
  const double conv_rot = cfg.converge_rot_deg * M_PI / 180.0;
  for (int level = PatchPyramid::kLevels - 1; level >= 0; --level) {
    NavState x_prev = x;
    double prev_mse = std::numeric_limits<double>::infinity();
    for (int it = 0; it < cfg.max_iterations; ++it) {
      const Linearization lin = linearize(x, gray, cam, T_imu_camera, pts, level, inv_var, cfg.estimate_exposure, pool);
      if (lin.n == 0) break;
      const double mse = lin.cost / double(lin.n);
      if (mse > prev_mse) {  // the last step made things worse: undo it and end this level
        x = x_prev;
        ++res.rollbacks;
        break;
      }
      prev_mse = mse;
      x_prev = x;
      StateCov info = P_prop_inv;
      info.topLeftCorner<7, 7>() += lin.HtRH;
      K_bar = info.ldlt().solve(StateCov::Identity());
      have_K = true;
      const StateVec Delta = x_prop.boxminus(x);
      StateVec g = StateVec::Zero();
      g.head<7>() = lin.HtRz + lin.HtRH * Delta.head<7>();
      const StateVec delta = Delta - K_bar * g;
      x = x.boxplus(delta);
      ++res.iterations;
      if (delta.segment<3>(sidx::kRot).norm() < conv_rot && delta.segment<3>(sidx::kPos).norm() < cfg.converge_pos_m)
        break;
    }
  }
  return have_K;
}

/// Step 4. Per-point errors and pixels at the posterior (the visual map drops points that stay bad).
void posteriorErrors(const NavState& x, const Image& gray, const CameraModel& cam, const Pose& T_imu_camera,
                     const std::vector<PointState>& pts, VioUpdateResult& res, WorkerPool* pool) {
  const Pose T_cw_post = (x.pose() * T_imu_camera).inverse();
  forRange(pool, pts.size(), kPointBlock, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      if (!pts[i].ref) continue;
      cam.project(T_cw_post * pts[i].point->p_world, res.point_px[i]);
      if (pts[i].used) res.point_rms[i] = pointRms(x, gray, cam, T_imu_camera, pts[i], 0);
    }
  });
  double sq_after = 0;
  int n_after = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (pts[i].used && res.point_rms[i] >= 0) {
      sq_after += res.point_rms[i] * res.point_rms[i];
      ++n_after;
    }
  }
  res.rms_after = n_after ? std::sqrt(sq_after / n_after) : 0.0;
}

}  // namespace

PhotometricNormalEquations photometricNormalEquations(const NavState& x, const Image& gray, const CameraModel& cam,
                                                      const Pose& T_imu_camera, const std::vector<const VisualPoint*>& points,
                                                      const std::vector<Eigen::Matrix2d>& warps, int level,
                                                      double inv_var, bool exposure) {
  std::vector<PointState> pts;
  for (std::size_t i = 0; i < points.size() && i < warps.size(); ++i) {
    PointState ps;
    ps.point = points[i];
    ps.ref = points[i] ? points[i]->referenceObs() : nullptr;
    if (!ps.ref) continue;
    ps.A = warps[i];
    ps.used = true;
    precomputeReference(ps);
    pts.push_back(ps);
  }
  const Linearization lin = linearize(x, gray, cam, T_imu_camera, pts, level, inv_var, exposure, nullptr);
  PhotometricNormalEquations out;
  out.HtRH = lin.HtRH;
  out.HtRz = lin.HtRz;
  out.cost = lin.cost;
  out.pixels = lin.n;
  return out;
}

VioUpdateResult visualUpdate(NavState& x, StateCov& P, const Image& gray, const CameraModel& cam,
                             const Pose& T_imu_camera, const std::vector<VisualPoint*>& points, const VioConfig& cfg,
                             WorkerPool* pool) {
  VioUpdateResult res;
  res.point_rms.assign(points.size(), -1.0);
  res.point_px.assign(points.size(), Vec2::Zero());
  // 1. Warps and the outlier gate at the prior.
  std::vector<PointState> pts;
  const double sq_before = gatePoints(x, gray, cam, T_imu_camera, points, cfg, pts, res, pool);
  if (res.points_used == 0) return res;
  res.rms_before = std::sqrt(sq_before / res.points_used);
  // 2. Iterated updates, coarse to fine.
  StateCov K_bar = P;
  // 3. Covariance once, from the last linearisation: P = (I - K_bar H^T R^-1 H) P_prop = K_bar.
  if (iterateLevels(x, P, gray, cam, T_imu_camera, pts, cfg, K_bar, res, pool)) P = 0.5 * (K_bar + K_bar.transpose());
  // 4. Per-point errors at the posterior.
  posteriorErrors(x, gray, cam, T_imu_camera, pts, res, pool);
  return res;
}

}  // namespace livo
