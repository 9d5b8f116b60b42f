#include "livo/estimation/state.hpp"

namespace livo {

NavState NavState::boxplus(const StateVec& d) const {
  NavState x = *this;
  x.R_world_imu = R_world_imu * expSO3(d.segment<3>(sidx::kRot));
  x.p_world_imu += d.segment<3>(sidx::kPos);
  x.inv_exposure += d[sidx::kExposure];
  x.v_world += d.segment<3>(sidx::kVel);
  x.bg += d.segment<3>(sidx::kBg);
  x.ba += d.segment<3>(sidx::kBa);
  x.g_world += d.segment<3>(sidx::kGrav);
  x.time_offset_s += d[sidx::kTimeOffset];
  return x;
}

StateVec NavState::boxminus(const NavState& o) const {
  StateVec d;
  d.segment<3>(sidx::kRot) = logSO3(o.R_world_imu.transpose() * R_world_imu);
  d.segment<3>(sidx::kPos) = p_world_imu - o.p_world_imu;
  d[sidx::kExposure] = inv_exposure - o.inv_exposure;
  d.segment<3>(sidx::kVel) = v_world - o.v_world;
  d.segment<3>(sidx::kBg) = bg - o.bg;
  d.segment<3>(sidx::kBa) = ba - o.ba;
  d.segment<3>(sidx::kGrav) = g_world - o.g_world;
  d[sidx::kTimeOffset] = time_offset_s - o.time_offset_s;
  return d;
}

Pose NavState::pose() const {
  Pose T = Pose::Identity();
  T.linear() = R_world_imu;
  T.translation() = p_world_imu;
  return T;
}

StateCov initialCovariance() {
  StateCov P = StateCov::Identity() * 0.01;
  P(sidx::kExposure, sidx::kExposure) = 1e-5;
  for (int i = sidx::kBg; i < sidx::kGrav + 3; ++i) P(i, i) = 1e-5;
  P(sidx::kTimeOffset, sidx::kTimeOffset) = 1e-6;
  return P;
}

}  // namespace livo
