#include "livo/estimation/frame_selector.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace livo {

double FrameSelector::translationThreshold(double sigma_min) const {
  return std::sqrt(3.0) * sigma_min * cfg_.tau_translation_m;
}

double FrameSelector::rotationThreshold(double sigma_min) const {
  return std::sqrt(3.0) * sigma_min * cfg_.tau_rotation_deg * M_PI / 180.0;
}

namespace {

/// P_after^-1 - P_before^-1 of one 3x3 marginal, symmetric positive semi-definite (zero when either
/// is not positive definite).
Mat3 marginalGain(const Mat3& before, const Mat3& after) {
  const Eigen::LLT<Mat3> b(before), a(after);
  if (b.info() != Eigen::Success || a.info() != Eigen::Success) return Mat3::Zero();
  Mat3 I = a.solve(Mat3::Identity()) - b.solve(Mat3::Identity());
  I = 0.5 * (I + I.transpose()).eval();
  // Rounding can leave small negative eigenvalues: an update never removes information.
  const Eigen::SelfAdjointEigenSolver<Mat3> es(I);
  if (es.info() != Eigen::Success) return Mat3::Zero();
  I = es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() * es.eigenvectors().transpose();
  return I.allFinite() ? I : Mat3::Zero();
}

/// Largest lambda of I v = lambda P^-1 v: the eigenvalues of L^T I L with P = L L^T (0 when P is not
/// positive definite).
double gainRatio(const Mat3& I, const Mat3& P) {
  const Eigen::LLT<Mat3> llt(P);
  if (llt.info() != Eigen::Success) return 0.0;
  const Mat3 L = llt.matrixL();
  const Eigen::SelfAdjointEigenSolver<Mat3> es(L.transpose() * I * L, Eigen::EigenvaluesOnly);
  if (es.info() != Eigen::Success) return 0.0;
  const double lambda = es.eigenvalues()(2);
  return std::isfinite(lambda) ? lambda : 0.0;
}

}  // namespace

FrameSelector::PoseInfo poseInformationGain(const NavState& x, const StateCov& P_before, const StateCov& P_after) {
  constexpr int r = sidx::kRot, p = sidx::kPos;
  const Mat3& R = x.R_world_imu;  // position information in body-frame errors: R^T I_w R
  FrameSelector::PoseInfo I;
  I.rotation = marginalGain(P_before.block<3, 3>(r, r), P_after.block<3, 3>(r, r));
  I.position_body = R.transpose() * marginalGain(P_before.block<3, 3>(p, p), P_after.block<3, 3>(p, p)) * R;
  return I;
}

double FrameSelector::informationRatio(const NavState& x, const StateCov& P) const {
  if (!have_last_) return 0.0;
  constexpr int r = sidx::kRot, p = sidx::kPos;
  const Mat3& R = x.R_world_imu;
  return std::max(gainRatio(last_info_.rotation, P.block<3, 3>(r, r)),
                  gainRatio(R * last_info_.position_body * R.transpose(), P.block<3, 3>(p, p)));
}

bool FrameSelector::select(const NavState& x, const StateCov& P, double sigma_min, bool degenerate) const {
  switch (mode_) {
    case VisualMode::Off: return false;
    case VisualMode::All: return true;
    case VisualMode::Adaptive: break;
  }
  if (degenerate || !have_last_ || !constrained_once_) return true;
  const double dt = (x.p_world_imu - last_.p_world_imu).norm();
  const double dr = rotationAngle(last_.R_world_imu.transpose() * x.R_world_imu);
  if (dt > translationThreshold(sigma_min) || dr > rotationThreshold(sigma_min)) return true;
  return cfg_.information_ratio > 0 && informationRatio(x, P) >= cfg_.information_ratio;
}

void FrameSelector::markUsed(const NavState& x, const StateCov& P_before, const StateCov& P_after) {
  last_ = x;
  have_last_ = true;
  last_info_ = poseInformationGain(x, P_before, P_after);
}

}  // namespace livo
