#include "livo/estimation/undistort.hpp"

#include "livo/map/point_cov.hpp"
#include "livo/sensors/downsample.hpp"

#include <algorithm>
#include <cmath>

namespace livo {

namespace {

/// What is fixed over one IMU interval of the trace, for points inside it: the interval's
/// rotation axis and rate, and the pose of its start composed with the inverse end pose, so that a point
/// costs one sin / cos and a few products instead of a search, an expSO3 and three pose products.
struct Interval {
  Utime t0 = 0;
  Mat3 R_end_k;        ///< R_end^T R_k
  Vec3 p_end_k;        ///< R_end^T (p_k - p_end)
  Vec3 v_end, a_end;   ///< R_end^T v_k, R_end^T a_k (0.5 a dt^2 below)
  Vec3 axis;           ///< omega / |omega| (zero when the rate is zero)
  double rate = 0.0;   ///< |omega|, rad/s

  Interval(const ImuTracePoint& k, const Pose& T_end_inv) : t0(k.utime) {
    const Mat3& Re = T_end_inv.linear();
    R_end_k = Re * k.R_world_imu;
    p_end_k = T_end_inv * k.p_world_imu;
    v_end = Re * k.v_world;
    a_end = Re * k.acc_world;
    rate = k.omega.norm();
    axis = rate > 0.0 ? Vec3(k.omega / rate) : Vec3::Zero();
  }

  /// R_end^T (R_k Exp(omega dt) q + p_k + v dt + a dt^2 / 2 - p_end): Rodrigues applied to the vector.
  Vec3 toEnd(const Vec3& q, double dt) const {
    Vec3 r = q;
    if (rate > 0.0) {
      const double th = rate * dt;
      double s, c1;  // sin(th), 1 - cos(th)
      if (std::abs(th) < 0.1) {
        // Within one IMU interval the angle is small: the series to th^6 agrees with sin / cos to
        // 2e-11 relative (th^7 / 5040), at a fraction of their cost.
        const double t2 = th * th;
        s = th * (1.0 - t2 / 6.0 * (1.0 - t2 / 20.0));
        c1 = t2 * 0.5 * (1.0 - t2 / 12.0 * (1.0 - t2 / 30.0));
      } else {
        s = std::sin(th);
        c1 = 1.0 - std::cos(th);
      }
      const Vec3 kq = axis.cross(q);
      r += s * kq + c1 * axis.cross(kq);
    }
    return R_end_k * r + p_end_k + v_end * dt + (0.5 * dt * dt) * a_end;
  }
};

}  // namespace

std::vector<LidarPoint> undistortToEnd(const LidarScan& sweep, const std::vector<ImuTracePoint>& trace,
                                       const Pose& T_imu_lidar) {
  std::vector<LidarPoint> out;
  out.reserve(sweep.points.size());
  if (trace.empty()) return out;
  const Pose T_end_inv = ImuPropagator::poseAt(trace, trace.back().utime).inverse();
  // The trace point each point falls into (the last with utime <= t, else the first): found by walking
  // forward along time-sorted points, by a binary search when a point goes back in time.
  std::size_t k = 0;
  std::size_t built = 0;  // the trace index `cur` was built for
  Interval cur(trace.front(), T_end_inv);
  const auto locate = [&](Utime t) {
    if (k + 1 < trace.size() && trace[k + 1].utime <= t) {
      ++k;  // the common case: the next interval
      while (k + 1 < trace.size() && trace[k + 1].utime <= t) ++k;
    } else if (trace[k].utime > t && k > 0) {
      const auto it = std::upper_bound(trace.begin(), trace.end(), t,
                                       [](Utime v, const ImuTracePoint& tp) { return v < tp.utime; });
      k = it == trace.begin() ? 0 : std::size_t(it - trace.begin()) - 1;
    }
  };
  for (const auto& p : sweep.points) {
    const Utime t = sweep.utime + fromSeconds(p.time_offset_s);
    locate(t);
    if (built != k) {
      cur = Interval(trace[k], T_end_inv);
      built = k;
    }
    LidarPoint q = p;
    q.p_lidar = cur.toEnd(T_imu_lidar * p.p_lidar.cast<double>(), toSeconds(t - cur.t0)).cast<float>();
    out.push_back(q);
  }
  return out;
}

std::vector<BodyPoint> prepareScan(const LidarScan& sweep, const std::vector<ImuTracePoint>& trace,
                                   const Pose& T_imu_lidar, const LioConfig& lio) {
  // Undistort every point to the frame time, then downsample in the IMU frame (FAST-LIVO2 order).
  std::vector<LidarPoint> undistorted = undistortToEnd(sweep, trace, T_imu_lidar);
  if (lio.downsample_m > 0) undistorted = voxelDownsample(undistorted, static_cast<float>(lio.downsample_m));
  // Uniform subsampling beyond the point cap keeps the cost per frame bounded.
  const std::size_t n = undistorted.size();
  const std::size_t cap = static_cast<std::size_t>(lio.max_points);
  const double stride = n > cap ? double(n) / double(cap) : 1.0;
  std::vector<BodyPoint> pts;
  pts.reserve(std::min(n, cap));
  const Mat3 R_il = T_imu_lidar.linear();
  const Pose T_lidar_imu = T_imu_lidar.inverse();
  for (double f = 0; f < double(n); f += stride) {
    const LidarPoint& lp = undistorted[static_cast<std::size_t>(f)];
    BodyPoint bp;
    bp.p_imu = lp.p_lidar.cast<double>();
    // Range/bearing covariance in the LiDAR frame, rotated into the IMU frame.
    const Mat3 cov_l = pointCovarianceBody(T_lidar_imu * bp.p_imu, lio.range_noise_m, lio.beam_noise_deg);
    bp.cov_imu = R_il * cov_l * R_il.transpose();
    pts.push_back(bp);
  }
  return pts;
}

}  // namespace livo
