// SO(3) / SE(3) helpers on Eigen.
//
// Conventions: rotation vectors (axis * angle, rad); Exp/Log are the group exponential and logarithm;
// the right Jacobian Jr(phi) satisfies Exp(phi + dphi) ~= Exp(phi) Exp(Jr(phi) dphi) (Forster et al.,
// "On-Manifold Preintegration", eqs. 7-9). Poses are Eigen::Isometry3d T_a_b mapping b-frame points
// into frame a. Poses in files and messages are [x, y, z, qx, qy, qz, qw].
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>

namespace livo {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Quat = Eigen::Quaterniond;
using Pose = Eigen::Isometry3d;

/// Skew-symmetric matrix [v]x with [v]x w = v x w.
Mat3 hat(const Vec3& v);
/// Inverse of hat() (reads the off-diagonal entries of a skew matrix).
Vec3 vee(const Mat3& m);

/// SO(3) exponential (Rodrigues), exact for all angles, series near zero.
Mat3 expSO3(const Vec3& phi);
/// SO(3) logarithm, angle in [0, pi]; accurate near 0 and near pi (input is re-orthonormalised).
Vec3 logSO3(const Mat3& R);
/// Right Jacobian of SO(3) and its inverse.
Mat3 rightJacobianSO3(const Vec3& phi);
Mat3 rightJacobianInvSO3(const Vec3& phi);
/// Left Jacobian: Jl(phi) = Jr(-phi).
Mat3 leftJacobianSO3(const Vec3& phi);

/// SE(3) exponential of xi = [rho (translation part); phi (rotation part)].
Pose expSE3(const Vec6& xi);
/// SE(3) logarithm, inverse of expSE3.
Vec6 logSE3(const Pose& T);

/// Pose from / to [x, y, z, qx, qy, qz, qw]. The quaternion is normalised (throws on zero norm);
/// poseToArray returns the sign with qw >= 0.
Pose poseFromArray(const double* xyz_qxyzw);
std::array<double, 7> poseToArray(const Pose& T);

/// Angle of a rotation in radians (0..pi).
double rotationAngle(const Mat3& R);

}  // namespace livo
