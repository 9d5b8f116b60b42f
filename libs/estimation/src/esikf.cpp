#include "livo/estimation/esikf.hpp"

namespace livo {

void Esikf::start(const NavState& x, const StateCov& P, double accel_scale, bool time_offset_prior_in_P) {
  x_ = x;
  P_ = P;
  propagator_ = std::make_unique<ImuPropagator>(imu_, accel_scale);
  time_offset_prior_set_ = time_offset_prior_in_P;
}

void Esikf::propagate(const std::vector<ImuSample>& samples, Utime t_end, std::vector<ImuTracePoint>* trace) {
  propagator_->propagate(x_, P_, samples, t_end, trace);
}

void Esikf::propagateBefore(const std::vector<ImuSample>& samples, Utime cut) {
  std::vector<ImuSample> before;
  for (const auto& s : samples)
    if (s.utime > x_.utime && s.utime < cut) before.push_back(s);
  if (!before.empty() && cut > x_.utime) propagator_->propagate(x_, P_, before, cut, nullptr);
}

void Esikf::setTimeOffsetPrior(double sigma_s) {
  constexpr int td = sidx::kTimeOffset;
  x_.time_offset_s = 0.0;
  P_.row(td).setZero();
  P_.col(td).setZero();
  P_(td, td) = sigma_s * sigma_s;
  time_offset_prior_set_ = true;
}

}  // namespace livo
