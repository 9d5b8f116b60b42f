#include "livo/eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace livo {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

std::vector<Vec3> positionsOf(const std::vector<Pose>& poses) {
  std::vector<Vec3> p;
  p.reserve(poses.size());
  for (const Pose& T : poses) p.push_back(T.translation());
  return p;
}

}  // namespace

ErrorStats errorStats(std::vector<double> errors) {
  ErrorStats s;
  s.count = errors.size();
  if (errors.empty()) return s;
  double sum = 0, sum_sq = 0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  const double n = double(errors.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  s.std = std::sqrt(std::max(0.0, sum_sq / n - s.mean * s.mean));
  std::sort(errors.begin(), errors.end());
  const std::size_t mid = errors.size() / 2;
  s.median = errors.size() % 2 ? errors[mid] : 0.5 * (errors[mid - 1] + errors[mid]);
  s.min = errors.front();
  s.max = errors.back();
  return s;
}

AteResult computeAte(const std::vector<Pose>& gt, const std::vector<Pose>& est_aligned) {
  if (gt.size() != est_aligned.size())
    throw std::invalid_argument("computeAte: " + std::to_string(gt.size()) + " ground-truth vs " +
                                std::to_string(est_aligned.size()) + " estimated poses");
  std::vector<double> trans, rot;
  trans.reserve(gt.size());
  rot.reserve(gt.size());
  for (std::size_t i = 0; i < gt.size(); ++i) {
    trans.push_back((gt[i].translation() - est_aligned[i].translation()).norm());
    rot.push_back(rotationAngle(gt[i].linear().transpose() * est_aligned[i].linear()) * kRadToDeg);
  }
  return {errorStats(std::move(trans)), errorStats(std::move(rot))};
}

RpeResult computeRpe(const std::vector<Pose>& gt, const std::vector<Pose>& est, double delta_m) {
  if (gt.size() != est.size())
    throw std::invalid_argument("computeRpe: " + std::to_string(gt.size()) + " ground-truth vs " +
                                std::to_string(est.size()) + " estimated poses");
  if (!(delta_m > 0.0)) throw std::invalid_argument("computeRpe: delta must be > 0 m");
  const std::vector<double> dist = cumulativeDistance(positionsOf(gt));
  std::vector<double> trans, rot;
  std::size_t j = 0;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    // First j with dist[j] - dist[i] >= delta; dist is non-decreasing, so j only moves forward.
    j = std::max(j, i);
    while (j < gt.size() && dist[j] - dist[i] < delta_m) ++j;
    if (j == gt.size()) break;  // later starts are even shorter
    const Pose rel_gt = gt[i].inverse() * gt[j];
    const Pose rel_est = est[i].inverse() * est[j];
    // rel_est is built from a possibly scaled est: its linear part is orthonormal (Sim3::apply keeps
    // R orthonormal), so inverse() is a rigid inverse.
    const Pose E = rel_gt.inverse() * rel_est;
    trans.push_back(E.translation().norm());
    rot.push_back(rotationAngle(E.linear()) * kRadToDeg);
  }
  RpeResult r;
  r.delta_m = delta_m;
  r.translation_m = errorStats(std::move(trans));
  r.rotation_deg = errorStats(std::move(rot));
  if (r.translation_m.count > 0) {
    r.translation_pct = r.translation_m.mean / delta_m * 100.0;
    r.rotation_deg_per_m = r.rotation_deg.mean / delta_m;
  }
  return r;
}

std::vector<double> cumulativeDistance(const std::vector<Vec3>& positions) {
  std::vector<double> d(positions.size(), 0.0);
  for (std::size_t k = 1; k < positions.size(); ++k) d[k] = d[k - 1] + (positions[k] - positions[k - 1]).norm();
  return d;
}

double pathLength(const std::vector<Vec3>& positions) {
  return positions.empty() ? 0.0 : cumulativeDistance(positions).back();
}

std::vector<double> defaultRpeDeltas(double path_length_m) {
  std::vector<double> deltas;
  if (!(path_length_m >= 1e-3) || !std::isfinite(path_length_m)) return deltas;
  for (double fraction : {0.1, 0.25, 0.5}) {
    const double target = fraction * path_length_m;
    const double decade = std::pow(10.0, std::floor(std::log10(target)));
    double nice = decade;
    for (double m : {2.0, 5.0, 10.0})
      if (m * decade <= target * (1 + 1e-9)) nice = m * decade;
    if (deltas.empty() || nice > deltas.back() * (1 + 1e-9)) deltas.push_back(nice);
  }
  return deltas;
}

}  // namespace livo
