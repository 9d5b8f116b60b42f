#include "livo/estimation/vio_update.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace livo {

void VioConfig::load(const ConfigNode& root) {
  const ConfigNode n = root.section("vio");
  n.get("max_iterations", max_iterations).get("outlier_rms", outlier_rms);
  n.get("estimate_exposure", estimate_exposure).get("normal_warp", normal_warp);
  n.get("converge_rot_deg", converge_rot_deg).get("converge_pos_m", converge_pos_m).get("model_noise", model_noise);
  n.check(model_noise >= 0, "model_noise", "must be >= 0");
  n.check(max_iterations >= 1 && max_iterations <= 50, "max_iterations", "must be in 1..50");
  n.check(outlier_rms > 0, "outlier_rms", "must be > 0");
}

void VioConfig::takeCamera(const CameraConfig& camera) {
  pixel_noise = camera.pixel_noise;
  estimate_time_offset = camera.estimate_time_offset;
  time_offset_sigma_s = camera.time_offset_sigma_s;
  camera_rate_hz = camera.rate_hz;
}

namespace {

using Row7 = Eigen::Matrix<double, 1, 7>;
using Mat8 = Eigen::Matrix<double, 8, 8>;
using Vec8 = Eigen::Matrix<double, 8, 1>;
/// The update's error-state entries: [dtheta, dp, dtau] and, last, dt_d (lin index 7).
constexpr int kTd = 7;

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
  Mat8 HtRH = Mat8::Zero();
  Vec8 HtRz = Vec8::Zero();
  double cost = 0.0;
  std::size_t n = 0;
};

/// The IMU pose at the capture time and what the Jacobians need of it, once per state (t_d = 0: the
/// state's pose, R_omega the identity).
struct CapturePose {
  Mat3 R_omega;  // Exp(omega t_d)
  Mat3 R;        // world <- imu at capture
  Vec3 p;
  Vec3 omega, v_world;
  CapturePose(const NavState& x, const CaptureMotion& m)
      : R_omega(expSO3(m.omega_imu * x.time_offset_s)),
        R(x.R_world_imu * R_omega),
        p(x.p_world_imu + x.v_world * x.time_offset_s),
        omega(m.omega_imu),
        v_world(x.v_world) {}
  Pose pose() const {
    Pose T = Pose::Identity();
    T.linear() = R;
    T.translation() = p;
    return T;
  }
};

bool projectPoint(const CapturePose& cp, const Pose& T_imu_camera, const CameraModel& cam, const Vec3& p_w, Vec3& p_i,
                  Vec3& p_c, Vec2& px, Eigen::Matrix<double, 2, 3>* J) {
  p_i = cp.R.transpose() * (p_w - cp.p);
  p_c = T_imu_camera.linear().transpose() * (p_i - T_imu_camera.translation());
  return cam.project(p_c, px, J);
}

}  // namespace

Pose imuPoseAtCapture(const NavState& x, const CaptureMotion& m) { return CapturePose(x, m).pose(); }

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
  Vec2 J_td = Vec2::Zero();                                                   // d px / d t_d (with_td)
};

bool projectForPatch(const CapturePose& cp, const Pose& T_imu_camera, const CameraModel& cam, const Vec3& p_w,
                     bool with_jacobian, PointProjection& out, bool with_td = false) {
  Vec3 p_c;
  Eigen::Matrix<double, 2, 3> J;
  if (!projectPoint(cp, T_imu_camera, cam, p_w, out.p_i, p_c, out.px, with_jacobian ? &J : nullptr)) return false;
  if (with_jacobian) {
    const Mat3 R_ci = T_imu_camera.linear().transpose();
    // R_capture = R Exp(dtheta) R_omega: p_i -> p_i + R_omega^T [R_omega p_i]x dtheta; p_i -> p_i - R_capture^T dp.
    out.J_theta = J * R_ci * (cp.R_omega.transpose() * hat(cp.R_omega * out.p_i));
    out.J_pos = -J * R_ci * cp.R.transpose();
    // d p_i / d t_d = -omega x p_i - R_capture^T v (uniform motion over t_d).
    if (with_td) out.J_td = J * R_ci * (-cp.omega.cross(out.p_i) - cp.R.transpose() * cp.v_world);
  }
  return true;
}

/// Residual of one patch pixel given the point's projection (see photometricResidual).
bool pixelResidual(const NavState& x, const Image& gray, const VisualObservation& ref, const Eigen::Matrix2d& A,
                   const PointProjection& pp, int level, int row, int col, bool with_jacobian, double& r,
                   Eigen::Matrix<double, 1, 7>* H, double* H_td) {
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
    if (H_td) *H_td = g * pp.J_td;
  }
  return true;
}

}  // namespace

bool photometricResidual(const NavState& x, const Image& gray, const CameraModel& cam, const Pose& T_imu_camera,
                         const VisualPoint& p, const Eigen::Matrix2d& A, int level, int row, int col, double& r,
                         Row7* H, const CaptureMotion* motion, double* H_td) {
  const VisualObservation* ref = p.referenceObs();
  if (!ref) return false;
  PointProjection pp;
  const CapturePose cp(x, motion ? *motion : CaptureMotion{});
  if (!projectForPatch(cp, T_imu_camera, cam, p.p_world, H != nullptr, pp, H_td != nullptr)) return false;
  return pixelResidual(x, gray, *ref, A, pp, level, row, col, H != nullptr, r, H, H_td);
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
double pointRms(const NavState& x, const CapturePose& cp, const Image& gray, const CameraModel& cam, const Pose& T_ic,
                const PointState& ps, int level) {
  PointProjection pp;
  if (!projectForPatch(cp, T_ic, cam, ps.point->p_world, false, pp)) return -1.0;
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

/// What the update linearises: the capture pose at the state, whether t_d is estimated, the terms.
struct LinearizeSpec {
  const CaptureMotion* motion = nullptr;
  int level = 0;
  double inv_var = 1.0;
  bool exposure = true;
  bool time_offset = false;
};

/// Adds one point's patch to the normal equations: the pixel rows are [g J_theta, g J_pos, I, g J_td] in
/// lin order [dtheta, dp, dtau, dt_d]; J (2 x kJ) is their image-gradient part without the dtau column,
/// kJ = 7 with the dt_d column (lin index kTd) when t_d is estimated, 6 without (its entries stay 0).
template <int kJ>
void addPointRows(const PointProjection& pp, const PatchMoments& m, double inv_var, bool exposure, Linearization& lin) {
  Eigen::Matrix<double, 2, kJ> J;
  J.template leftCols<3>() = pp.J_theta;
  J.template middleCols<3>(3) = pp.J_pos;
  if constexpr (kJ == 7) J.col(6) = pp.J_td;
  const Eigen::Matrix<double, kJ, kJ> JgJ = inv_var * (J.transpose() * m.gg * J);
  const Eigen::Matrix<double, kJ, 1> Jgr = inv_var * (J.transpose() * m.gr);
  lin.HtRH.topLeftCorner<6, 6>() += JgJ.template topLeftCorner<6, 6>();
  lin.HtRz.head<6>() += Jgr.template head<6>();
  if constexpr (kJ == 7) {
    lin.HtRH.block<6, 1>(0, kTd) += JgJ.template block<6, 1>(0, 6);
    lin.HtRH.block<1, 6>(kTd, 0) += JgJ.template block<1, 6>(6, 0);
    lin.HtRH(kTd, kTd) += JgJ(6, 6);
    lin.HtRz(kTd) += Jgr(6);
  }
  if (!exposure) return;
  const Eigen::Matrix<double, kJ, 1> c = inv_var * (J.transpose() * m.gI);
  lin.HtRH.block<6, 1>(0, 6) += c.template head<6>();
  lin.HtRH.block<1, 6>(6, 0) += c.template head<6>().transpose();
  if constexpr (kJ == 7) {
    lin.HtRH(kTd, 6) += c(6);
    lin.HtRH(6, kTd) += c(6);
  }
  lin.HtRH(6, 6) += inv_var * m.II;
  lin.HtRz(6) += inv_var * m.Ir;
}

/// Adds points [begin, end) of `pts` to `lin`.
void linearizeBlock(const NavState& x, const CapturePose& cp, const Image& gray, const CameraModel& cam, const Pose& T_ic,
                    const std::vector<PointState>& pts, std::size_t begin, std::size_t end, const LinearizeSpec& spec,
                    Linearization& out) {
  Linearization lin;  // local, stored once at the end: no cache line shared with a neighbour block meanwhile
  CurrentGrid grid;
  const double inv_var = spec.inv_var;
  for (std::size_t i = begin; i < end; ++i) {
    const PointState& ps = pts[i];
    if (!ps.used) continue;
    PointProjection pp;
    if (!projectForPatch(cp, T_ic, cam, ps.point->p_world, true, pp, spec.time_offset)) continue;
    grid.sample(gray, pp.px, spec.level);
    const PatchMoments m = patchMoments(x, grid, ps, spec.level);
    if (m.n == 0) continue;
    if (spec.time_offset)
      addPointRows<7>(pp, m, inv_var, spec.exposure, lin);
    else
      addPointRows<6>(pp, m, inv_var, spec.exposure, lin);
    lin.cost += m.rr;
    lin.n += m.n;
  }
  out = lin;
}

/// Normal equations of every used point at spec.level: blocks of points in parallel on `pool`, summed
/// in block order.
Linearization linearize(const NavState& x, const Image& gray, const CameraModel& cam, const Pose& T_ic,
                        const std::vector<PointState>& pts, const LinearizeSpec& spec, WorkerPool* pool) {
  const CapturePose cp(x, spec.motion ? *spec.motion : CaptureMotion{});
  std::vector<Linearization> blocks((pts.size() + kPointBlock - 1) / kPointBlock);
  forRange(pool, pts.size(), kPointBlock, [&](std::size_t begin, std::size_t end) {
    linearizeBlock(x, cp, gray, cam, T_ic, pts, begin, end, spec, blocks[begin / kPointBlock]);
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
double gatePoints(const NavState& x, const CaptureMotion& motion, const Image& gray, const CameraModel& cam,
                  const Pose& T_imu_camera, const std::vector<VisualPoint*>& points, const VioConfig& cfg,
                  std::vector<PointState>& pts, VioUpdateResult& res, WorkerPool* pool) {
  const CapturePose cp(x, motion);
  const Pose T_world_camera = cp.pose() * T_imu_camera;
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
      rms[i] = pointRms(x, cp, gray, cam, T_imu_camera, ps, 0);
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
/// first 7 error-state entries) and, when estimated, dt_d, rolling back an iteration that raises the
/// mean squared error. Returns false when no iteration linearised anything (P stays the prior); else
/// `K_bar` is the posterior covariance of the last linearisation.
bool iterateLevels(NavState& x, const StateCov& P_prop, const Image& gray, const CameraModel& cam,
                   const Pose& T_imu_camera, const std::vector<PointState>& pts, const VioConfig& cfg,
                   const CaptureMotion& motion, StateCov& K_bar, VioUpdateResult& res, WorkerPool* pool) {
  const NavState x_prop = x;
  const StateCov P_prop_inv = P_prop.ldlt().solve(StateCov::Identity());
  bool have_K = false;
  const double conv_rot = cfg.converge_rot_deg * M_PI / 180.0;
  LinearizeSpec spec;
  spec.motion = &motion;
  spec.inv_var = 1.0 / cfg.residualVariance();
  spec.exposure = cfg.estimate_exposure;
  spec.time_offset = cfg.estimate_time_offset;
  for (int level = PatchPyramid::kLevels - 1; level >= 0; --level) {
    spec.level = level;
    NavState x_prev = x;
    double prev_mse = std::numeric_limits<double>::infinity();
    for (int it = 0; it < cfg.max_iterations; ++it) {
      const Linearization lin = linearize(x, gray, cam, T_imu_camera, pts, spec, pool);
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
      const StateVec Delta = x_prop.boxminus(x);
      StateVec g = StateVec::Zero();
      // The update's 8 entries in the state: the first 7 and t_d (a zero row and column unless estimated).
      constexpr int td = sidx::kTimeOffset;
      info.topLeftCorner<7, 7>() += lin.HtRH.topLeftCorner<7, 7>();
      info.block<7, 1>(0, td) += lin.HtRH.block<7, 1>(0, kTd);
      info.block<1, 7>(td, 0) += lin.HtRH.block<1, 7>(kTd, 0);
      info(td, td) += lin.HtRH(kTd, kTd);
      Vec8 d8;
      d8 << Delta.head<7>(), Delta(td);
      const Vec8 g8 = lin.HtRz + lin.HtRH * d8;
      g.head<7>() = g8.head<7>();
      g(td) = g8(kTd);
      K_bar = info.ldlt().solve(StateCov::Identity());
      have_K = true;
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
void posteriorErrors(const NavState& x, const CaptureMotion& motion, const Image& gray, const CameraModel& cam,
                     const Pose& T_imu_camera, const std::vector<PointState>& pts, VioUpdateResult& res,
                     WorkerPool* pool) {
  const CapturePose cp(x, motion);
  const Pose T_cw_post = (cp.pose() * T_imu_camera).inverse();
  forRange(pool, pts.size(), kPointBlock, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      if (!pts[i].ref) continue;
      cam.project(T_cw_post * pts[i].point->p_world, res.point_px[i]);
      if (pts[i].used) res.point_rms[i] = pointRms(x, cp, gray, cam, T_imu_camera, pts[i], 0);
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
  LinearizeSpec spec;
  spec.level = level;
  spec.inv_var = inv_var;
  spec.exposure = exposure;
  const Linearization lin = linearize(x, gray, cam, T_imu_camera, pts, spec, nullptr);
  PhotometricNormalEquations out;
  out.HtRH = lin.HtRH.topLeftCorner<7, 7>();
  out.HtRz = lin.HtRz.head<7>();
  out.cost = lin.cost;
  out.pixels = lin.n;
  return out;
}

VioUpdateResult visualUpdate(NavState& x, StateCov& P, const Image& gray, const CameraModel& cam,
                             const Pose& T_imu_camera, const std::vector<VisualPoint*>& points, const VioConfig& cfg,
                             WorkerPool* pool, const CaptureMotion& motion) {
  VioUpdateResult res;
  res.point_rms.assign(points.size(), -1.0);
  res.point_px.assign(points.size(), Vec2::Zero());
  // 1. Warps and the outlier gate at the prior.
  std::vector<PointState> pts;
  const double sq_before = gatePoints(x, motion, gray, cam, T_imu_camera, points, cfg, pts, res, pool);
  if (res.points_used == 0) return res;
  res.rms_before = std::sqrt(sq_before / res.points_used);
  // 2. Iterated updates, coarse to fine.
  StateCov K_bar = P;
  // 3. Covariance once, from the last linearisation: P = (I - K_bar H^T R^-1 H) P_prop = K_bar.
  if (iterateLevels(x, P, gray, cam, T_imu_camera, pts, cfg, motion, K_bar, res, pool)) P = 0.5 * (K_bar + K_bar.transpose());
  // 4. Per-point errors at the posterior.
  posteriorErrors(x, motion, gray, cam, T_imu_camera, pts, res, pool);
  return res;
}

}  // namespace livo
