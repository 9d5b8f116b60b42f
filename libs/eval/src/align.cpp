#include "livo/eval/align.hpp"

#include <Eigen/SVD>

#include <cmath>
#include <stdexcept>
#include <string>

namespace livo {

std::vector<PosePair> associate(const Trajectory& gt, const Trajectory& est, double max_dt_s,
                                double est_time_offset_s) {
  std::vector<PosePair> pairs;
  std::vector<double> pair_dt;  // |dt| of each kept pair, to resolve duplicates
  if (gt.empty() || est.empty()) return pairs;
  std::size_t g = 0;
  for (std::size_t e = 0; e < est.size(); ++e) {
    const double t = est[e].t + est_time_offset_s;
    // Advance g while the next ground-truth pose is at least as close (est times increase, so the
    // nearest ground-truth index never moves backwards).
    while (g + 1 < gt.size() && std::abs(gt[g + 1].t - t) <= std::abs(gt[g].t - t)) ++g;
    const double dt = std::abs(gt[g].t - t);
    if (!(dt <= max_dt_s)) continue;
    if (!pairs.empty() && pairs.back().gt_index == g) {
      // Same ground-truth pose as the previous pair: keep the closer one.
      if (dt < pair_dt.back()) {
        pairs.back().est_index = e;
        pair_dt.back() = dt;
      }
      continue;
    }
    pairs.push_back({g, e});
    pair_dt.push_back(dt);
  }
  return pairs;
}

Pose Sim3::rigid() const {
  Pose T = Pose::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Pose Sim3::apply(const Pose& T) const {
  Pose out = Pose::Identity();
  out.linear() = R * T.linear();
  out.translation() = apply(Vec3(T.translation()));
  return out;
}

Sim3 umeyama(const std::vector<Vec3>& src, const std::vector<Vec3>& dst, bool with_scale) {
  if (src.size() != dst.size())
    throw std::invalid_argument("umeyama: " + std::to_string(src.size()) + " source vs " +
                                std::to_string(dst.size()) + " destination points");
  const std::size_t n = src.size();
  if (n < 3) throw std::invalid_argument("umeyama: need at least 3 point pairs, got " + std::to_string(n));

  // Means (eqs. 34-35).
  Vec3 mu_src = Vec3::Zero(), mu_dst = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mu_src += src[i];
    mu_dst += dst[i];
  }
  mu_src /= double(n);
  mu_dst /= double(n);

  // Source variance (eq. 36) and cross-covariance Sigma_xy = 1/n sum (dst - mu_dst)(src - mu_src)^T (eq. 38).
  double var_src = 0.0;
  Mat3 cov = Mat3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 a = src[i] - mu_src;
    const Vec3 b = dst[i] - mu_dst;
    var_src += a.squaredNorm();
    cov += b * a.transpose();
  }
  var_src /= double(n);
  cov /= double(n);

  // SVD Sigma_xy = U D V^T; S = diag(1, 1, -1) when det(U) det(V) < 0 (eq. 39, no reflection).
  Eigen::JacobiSVD<Mat3> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Vec3 S = Vec3::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2) = -1.0;

  Sim3 result;
  result.R = svd.matrixU() * S.asDiagonal() * svd.matrixV().transpose();  // eq. 40
  if (with_scale) {
    if (!(var_src > 1e-12))
      throw std::invalid_argument("umeyama: source points coincide, scale is undefined");
    result.s = svd.singularValues().dot(S) / var_src;  // eq. 42: tr(DS) / sigma_x^2
  }
  result.t = mu_dst - result.s * result.R * mu_src;  // eq. 41
  return result;
}

}  // namespace livo
