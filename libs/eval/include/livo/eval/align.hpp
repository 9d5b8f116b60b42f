// Pose association by timestamp and least-squares trajectory alignment (Umeyama 1991).
#pragma once

#include "livo/eval/tum.hpp"

#include <cstddef>
#include <vector>

namespace livo {

/// One matched pair: gt[gt_index] and est[est_index], |t_gt - (t_est + offset)| <= max_dt.
struct PosePair {
  std::size_t gt_index = 0;
  std::size_t est_index = 0;
};

/// Matches every estimated pose to the ground-truth pose nearest in time (est times shifted by
/// `est_time_offset_s`), keeps pairs with |dt| <= max_dt_s, and makes the matching one-to-one: when
/// several estimated poses pick the same ground-truth pose, the closest in time wins (ties: the
/// earlier one). Both trajectories must be sorted by time (readTum guarantees it). Two pointers,
/// O(n + m). Pairs come out increasing in both indices.
std::vector<PosePair> associate(const Trajectory& gt, const Trajectory& est, double max_dt_s,
                                double est_time_offset_s = 0.0);

/// Similarity transform p -> s * R * p + t (an SE(3) when s = 1).
struct Sim3 {
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  double s = 1.0;

  Vec3 apply(const Vec3& p) const { return s * (R * p) + t; }
  /// The rigid part as a pose (scale dropped).
  Pose rigid() const;
  /// Maps a pose: rotation R * R_pose, position apply(p_pose). The result's rotation stays orthonormal.
  Pose apply(const Pose& T) const;
};

/// Umeyama's closed form (Umeyama, "Least-squares estimation of transformation parameters between
/// two point patterns", PAMI 1991, eqs. 34-42): the Sim3 (or SE(3) when !with_scale) minimising
/// sum_i |dst_i - (s R src_i + t)|^2. Reflections are excluded (S = diag(1, 1, -1) when
/// det(U) det(V) < 0, eq. 39). Throws std::invalid_argument when fewer than 3 points are given, the
/// sizes differ, or (with scale) all source points coincide. Collinear points leave the rotation about
/// the line unobservable; the result is then one of the minimisers. With zero-mean noise of variance
/// sigma^2 per axis on src, the scale is biased low by the factor var_src / (var_src + 3 sigma^2)
/// (errors in variables); rotation and translation of an SE(3) fit are not biased by it.
Sim3 umeyama(const std::vector<Vec3>& src, const std::vector<Vec3>& dst, bool with_scale);

}  // namespace livo
