// Field checks shared by map_messages.cpp and estimator_messages.cpp (private to libs/io).
//
// Every check returns an error RELATIVE to the message it inspects ("normal: ..."); the caller prefixes
// the message type or the nested path ("submap_t.planes[3].") with nest(), so strings are only built on
// failure and a message of 10k planes validates without allocating.
#pragma once

#include "livo/io/convert.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <string>

namespace livo {
namespace msgcheck {

#define LIVO_MSG_CHECK(expr)        \
  do {                              \
    ::livo::Validation v_ = (expr); \
    if (!v_) return v_;             \
  } while (0)

inline std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

/// Prefixes a failed validation with `prefix` + "." (ok stays ok).
inline Validation nest(Validation v, const std::string& prefix) {
  if (!v) v.error = prefix + "." + v.error;
  return v;
}

/// "planes: num_planes declares 5 but the array has 4 values"
template <class Vec>
Validation size(const Vec& v, std::int64_t n, const char* field, const char* count) {
  if (static_cast<std::int64_t>(v.size()) != n)
    return Validation::fail(std::string(field) + ": " + count + " declares " + std::to_string(n) +
                            " but the array has " + std::to_string(v.size()) + " values");
  return Validation::ok();
}

/// 0 <= n <= limit, the error names the count field and the MessageLimits member.
inline Validation count(std::int64_t n, std::int64_t limit, const char* field, const char* limit_name) {
  if (n < 0) return Validation::fail(std::string(field) + ": negative count " + std::to_string(n));
  if (n > limit)
    return Validation::fail(std::string(field) + ": " + std::to_string(n) + " exceeds MessageLimits::" + limit_name +
                            " = " + std::to_string(limit));
  return Validation::ok();
}

template <class T>
Validation finite(const T* v, int n, const char* field) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(static_cast<double>(v[i])))
      return Validation::fail(std::string(field) + "[" + std::to_string(i) + "]: non-finite value " + num(double(v[i])));
  return Validation::ok();
}

/// Finite and >= 0 (durations, radii, variances).
inline Validation nonNegative(double v, const char* field) {
  if (!std::isfinite(v) || v < 0.0)
    return Validation::fail(std::string(field) + ": expected a finite value >= 0, got " + num(v));
  return Validation::ok();
}

inline Validation utime(std::int64_t t, const char* field = "utime") {
  if (t < 0) return Validation::fail(std::string(field) + ": negative time " + std::to_string(t));
  return Validation::ok();
}

/// Unit vector: finite and | |n| - 1 | <= 1e-3.
inline Validation unitVector(const double* n, const char* field) {
  LIVO_MSG_CHECK(finite(n, 3, field));
  const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (std::abs(norm - 1.0) > 1e-3)
    return Validation::fail(std::string(field) + ": norm " + num(norm) + " is not 1 (tolerance 1e-3)");
  return Validation::ok();
}

/// Quaternion [qx, qy, qz, qw]: finite with norm > 1e-6 (it is normalised on the way in).
inline Validation quaternion(const double* q, const char* field) {
  LIVO_MSG_CHECK(finite(q, 4, field));
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(norm > 1e-6)) return Validation::fail(std::string(field) + ": quaternion norm " + num(norm) + " is (near) zero");
  if (!std::isfinite(norm)) return Validation::fail(std::string(field) + ": quaternion norm overflows (components too large)");
  return Validation::ok();
}

/// Pose [x, y, z, qx, qy, qz, qw].
inline Validation pose7(const double* T, const char* field) {
  LIVO_MSG_CHECK(finite(T, 7, field));
  return quaternion(T + 3, field);
}

/// Row-major n x n covariance: finite; diagonal >= -1e-9 max_diag (rounding of rank-deficient blocks);
/// symmetric within 1e-6 sqrt(c_ii c_jj) + 1e-9 max_diag; every 2x2 principal minor PSD with the same
/// slack, |c_ij| <= (1 + 1e-6) sqrt(c_ii c_jj) + 1e-9 max_diag. Not a full PSD test (that needs an
/// eigen decomposition), but it catches garbage, sign errors and transposed blocks.
inline Validation covariance(const double* c, int n, const char* field) {
  double max_diag = 0.0;
  for (int i = 0; i < n * n; ++i)
    if (!std::isfinite(c[i]))
      return Validation::fail(std::string(field) + ": non-finite value at (" + std::to_string(i / n) + "," +
                              std::to_string(i % n) + ")");
  for (int i = 0; i < n; ++i) max_diag = std::max(max_diag, c[i * n + i]);
  const double slack = 1e-9 * max_diag;
  for (int i = 0; i < n; ++i)
    if (c[i * n + i] < -slack)
      return Validation::fail(std::string(field) + ": negative variance " + num(c[i * n + i]) + " at (" +
                              std::to_string(i) + "," + std::to_string(i) + ")");
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const double a = c[i * n + j], b = c[j * n + i];
      const double bound = std::sqrt(std::max(c[i * n + i], 0.0) * std::max(c[j * n + j], 0.0));
      auto at = [&] { return " at (" + std::to_string(i) + "," + std::to_string(j) + ")"; };
      if (std::abs(a - b) > 1e-6 * bound + slack)
        return Validation::fail(std::string(field) + ": not symmetric" + at() + ": " + num(a) + " vs " + num(b));
      if (std::abs(a) > (1.0 + 1e-6) * bound + slack)
        return Validation::fail(std::string(field) + ": not positive semidefinite" + at() + ": |c_ij| = " +
                                num(std::abs(a)) + " > sqrt(c_ii c_jj) = " + num(bound));
    }
  return Validation::ok();
}

/// The navigation state fields odometry_t and filter_state_t share (utime, position, orientation,
/// velocity, biases, gravity, inv_exposure > 0).
template <class M>
Validation navState(const M& m) {
  LIVO_MSG_CHECK(utime(m.utime));
  LIVO_MSG_CHECK(finite(m.position, 3, "position"));
  LIVO_MSG_CHECK(quaternion(m.orientation, "orientation"));
  LIVO_MSG_CHECK(finite(m.velocity, 3, "velocity"));
  LIVO_MSG_CHECK(finite(m.gyro_bias, 3, "gyro_bias"));
  LIVO_MSG_CHECK(finite(m.accel_bias, 3, "accel_bias"));
  LIVO_MSG_CHECK(finite(m.gravity, 3, "gravity"));
  if (!std::isfinite(m.inv_exposure) || !(m.inv_exposure > 0.0))
    return Validation::fail("inv_exposure: expected a finite value > 0, got " + num(m.inv_exposure));
  return Validation::ok();
}

/// Symmetric 3x3 covariance stored as its upper triangle (xx, xy, xz, yy, yz, zz).
template <class T>
Validation covarianceUpper3(const T* u, const char* field) {
  const double c[9] = {double(u[0]), double(u[1]), double(u[2]), double(u[1]), double(u[3]),
                       double(u[4]), double(u[2]), double(u[4]), double(u[5])};
  return covariance(c, 3, field);
}

}  // namespace msgcheck
}  // namespace livo
