#include "livo/loop/place_descriptor.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <limits>

namespace livo {

void PlaceDescriptorConfig::load(const ConfigNode& loop, double lidar_max_range_m) {
  max_range_m = std::min(max_range_m, lidar_max_range_m);
  loop.get("descriptor_rings", rings).get("descriptor_sectors", sectors);
  loop.get("descriptor_min_range_m", min_range_m).get("descriptor_range_m", max_range_m);
  loop.get("descriptor_height_m", height_cap_m);
  loop.check(rings >= 2 && rings <= 200, "descriptor_rings", "must be in [2, 200]");
  loop.check(sectors >= 8 && sectors <= 720, "descriptor_sectors", "must be in [8, 720]");
  loop.check(std::isfinite(min_range_m) && min_range_m >= 0, "descriptor_min_range_m", "must be >= 0");
  loop.check(std::isfinite(max_range_m) && max_range_m > min_range_m, "descriptor_range_m",
             "must be greater than descriptor_min_range_m");
  loop.check(max_range_m <= lidar_max_range_m, "descriptor_range_m",
             "must not exceed lidar.max_range_m (" + std::to_string(lidar_max_range_m) + ")");
  loop.check(std::isfinite(height_cap_m) && height_cap_m > 0, "descriptor_height_m", "must be > 0");
}

double yawOf(const Pose& T_world_body) {
  const Mat3 R = T_world_body.linear();
  return std::atan2(R(1, 0), R(0, 0));
}

Pose keyframeFrame(const Pose& T_world_body) {
  Pose K = Pose::Identity();
  K.linear() = Eigen::AngleAxisd(yawOf(T_world_body), Vec3::UnitZ()).toRotationMatrix();
  K.translation() = T_world_body.translation();
  return K;
}

PlaceDescriptor PlaceDescriptor::computeAt(const std::vector<Vec3>& world_points, const Pose& T_world_body,
                                           const PlaceDescriptorConfig& cfg) {
  const Pose K_inv = keyframeFrame(T_world_body).inverse();
  std::vector<Vec3> local;
  local.reserve(world_points.size());
  for (const Vec3& p : world_points) local.push_back(K_inv * p);
  return compute(local, cfg);
}

PlaceDescriptor PlaceDescriptor::compute(const std::vector<Vec3>& points, const PlaceDescriptorConfig& cfg) {
  PlaceDescriptor d;
  d.rings_ = cfg.rings;
  d.sectors_ = cfg.sectors;
  const auto R = static_cast<std::size_t>(cfg.rings), S = static_cast<std::size_t>(cfg.sectors);
  d.cells_.assign(R * S, 0.f);
  d.col_norm_.assign(S, 0.f);
  d.ring_key_.assign(R, 0.f);

  // The cells' points: ring, sector and height; the floor is a low quantile of the heights, so that a
  // few points below the ground (noise, a kerb) do not lift every cell.
  struct Binned {
    std::size_t cell;
    double z;
  };
  std::vector<Binned> binned;
  binned.reserve(points.size());
  const double ring_w = (cfg.max_range_m - cfg.min_range_m) / cfg.rings;
  const double sector_w = 2.0 * M_PI / cfg.sectors;
  for (const Vec3& p : points) {
    if (!p.allFinite()) continue;
    const double r = std::hypot(p.x(), p.y());
    if (r <= cfg.min_range_m || r > cfg.max_range_m) continue;
    const auto ring = std::min(R - 1, static_cast<std::size_t>((r - cfg.min_range_m) / ring_w));
    const double a = std::atan2(p.y(), p.x()) + M_PI;  // [0, 2 pi]
    const auto sector = static_cast<std::size_t>(a / sector_w) % S;
    binned.push_back({ring * S + sector, p.z()});
  }
  if (binned.empty()) return d;
  std::vector<double> z(binned.size());
  for (std::size_t i = 0; i < binned.size(); ++i) z[i] = binned[i].z;
  const std::size_t q = binned.size() / 20;  // the 5 % quantile
  std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(q), z.end());
  const double floor_z = z[q];

  // An occupied cell is never 0, so that a cell on the floor still counts as seen.
  constexpr float kSeen = 1e-3f;
  for (const Binned& b : binned) {
    const double h = std::clamp((b.z - floor_z) / cfg.height_cap_m, 0.0, 1.0);
    d.cells_[b.cell] = std::max(d.cells_[b.cell], std::max(kSeen, static_cast<float>(h)));
  }
  d.summarise();
  return d;
}

PlaceDescriptor PlaceDescriptor::fromCells(int rings, int sectors, std::vector<float> cells) {
  if (rings <= 0 || sectors <= 0 || cells.size() != std::size_t(rings) * std::size_t(sectors))
    throw std::invalid_argument("place descriptor: " + std::to_string(cells.size()) + " cells for " +
                                std::to_string(rings) + " x " + std::to_string(sectors));
  for (const float c : cells)
    if (!(c >= 0.f && c <= 1.f)) throw std::invalid_argument("place descriptor: a cell outside [0, 1]");
  PlaceDescriptor d;
  d.rings_ = rings;
  d.sectors_ = sectors;
  d.cells_ = std::move(cells);
  d.summarise();
  return d;
}

void PlaceDescriptor::summarise() {
  const auto R = static_cast<std::size_t>(rings_), S = static_cast<std::size_t>(sectors_);
  ring_key_.assign(R, 0.f);
  col_norm_.assign(S, 0.f);
  PlaceDescriptor& d = *this;
  for (std::size_t r = 0; r < R; ++r) {
    double sum = 0.0;
    for (std::size_t s = 0; s < S; ++s) sum += d.cells_[r * S + s];
    d.ring_key_[r] = static_cast<float>(sum / static_cast<double>(S));
  }
  for (std::size_t s = 0; s < S; ++s) {
    double n2 = 0.0;
    for (std::size_t r = 0; r < R; ++r) n2 += double(d.cells_[r * S + s]) * d.cells_[r * S + s];
    d.col_norm_[s] = static_cast<float>(std::sqrt(n2));
  }
}

int PlaceDescriptor::occupiedSectors() const {
  return static_cast<int>(std::count_if(col_norm_.begin(), col_norm_.end(), [](float n) { return n > 0.f; }));
}

double PlaceDescriptor::ringKeyDistance(const PlaceDescriptor& candidate) const {
  if (candidate.rings_ != rings_ || rings_ == 0) return std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (int r = 0; r < rings_; ++r) sum += std::abs(double(ring_key_[r]) - candidate.ring_key_[r]);
  return sum / rings_;
}

double PlaceDescriptor::distanceAtShift(const PlaceDescriptor& c, int shift, int* compared) const {
  // Query column (s + shift) against the candidate's column s: a turn of +yaw moves a point's azimuth,
  // and so its sector, forward.
  double sum = 0.0;
  int n = 0;
  for (int s = 0; s < sectors_; ++s) {
    const int qs = (s + shift) % sectors_;
    const float nq = col_norm_[qs], nc = c.col_norm_[s];
    if (nq <= 0.f || nc <= 0.f) continue;
    double dot = 0.0;
    for (int r = 0; r < rings_; ++r) dot += double(cells_[r * sectors_ + qs]) * c.cells_[r * sectors_ + s];
    sum += 1.0 - dot / (double(nq) * nc);
    ++n;
  }
  *compared = n;
  return n > 0 ? sum / n : 1.0;
}

PlaceMatch PlaceDescriptor::match(const PlaceDescriptor& c) const {
  PlaceMatch m;
  if (c.rings_ != rings_ || c.sectors_ != sectors_ || rings_ == 0) return m;
  // Too few sectors seen by both leave nothing to compare: a quarter of the circle at least, or, for a
  // sensor that sees less (a 70 deg Avia fills about 12 of 60 sectors), half of what the narrower of the
  // two sees.
  const int min_compared = std::max(2, std::min(sectors_ / 4, std::min(occupiedSectors(), c.occupiedSectors()) / 2));
  std::vector<double> dist(static_cast<std::size_t>(sectors_), 1.0);
  int best = -1;
  for (int k = 0; k < sectors_; ++k) {
    int n = 0;
    const double dk = distanceAtShift(c, k, &n);
    if (n < min_compared) continue;
    dist[static_cast<std::size_t>(k)] = dk;
    if (best < 0 || dk < dist[static_cast<std::size_t>(best)]) {
      best = k;
      m.compared = n;
    }
  }
  if (best < 0) return m;
  m.shift = best;
  m.distance = dist[static_cast<std::size_t>(best)];
  // A parabola through the neighbours refines the shift to a fraction of a sector.
  const double dm = dist[static_cast<std::size_t>((best + sectors_ - 1) % sectors_)];
  const double dp = dist[static_cast<std::size_t>((best + 1) % sectors_)];
  const double curv = dm - 2.0 * m.distance + dp;
  const double frac = curv > 1e-12 ? std::clamp(0.5 * (dm - dp) / curv, -0.5, 0.5) : 0.0;
  double yaw = (best + frac) * 2.0 * M_PI / sectors_;
  if (yaw > M_PI) yaw -= 2.0 * M_PI;
  m.yaw_rad = yaw;
  return m;
}

}  // namespace livo
