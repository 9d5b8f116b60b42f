#include "livo/viewer/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace livo::viewer {

namespace {

constexpr double kRateWindowS = 2.0;

/// The q-quantile (0..1) of up to ~10,000 evenly spaced samples of `values`.
float quantile(const std::vector<float>& values, double q) {
  if (values.empty()) return 0.f;
  const std::size_t step = std::max<std::size_t>(1, values.size() / 10'000);
  std::vector<float> s;
  s.reserve(values.size() / step + 1);
  for (std::size_t i = 0; i < values.size(); i += step) s.push_back(values[i]);
  const auto k = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * double(s.size() - 1) + 0.5);
  std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(k), s.end());
  return s[k];
}

std::string fmt(const char* f, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b, c);
  return buf;
}

}  // namespace

std::string overlayText(const OverlayData& d) {
  std::string s = d.source + "\n";
  s += fmt("t %.1f s   frames %.0f   %.1f Hz", d.t_s, double(d.frames), d.rate_hz) + "\n";
  if (d.frame) {
    const FrameStatsInput& f = *d.frame;
    s += fmt("frame %.1f ms (lidar %.1f, visual %.1f)", f.total_ms, f.lio_ms, f.vio_ms) +
         fmt("   sigma_min %.3f", f.sigma_min) + (f.degenerate ? "   DEGENERATE" : "") +
         (f.visual_used ? "   visual update" : "") + (f.map_timeout ? "   MAP TIMEOUT" : "") + "\n";
    if (f.health == 2 || f.health == 3)  // the state and its reason, cut to one line
      s += std::string(f.health == 3 ? "LOST (do not navigate on this pose): " : "degraded: ") +
           f.health_reason.substr(0, 100) + "\n";
  }
  if (d.map) {
    s += fmt("map server %.1f MiB", double(d.map->bytes) / (1024.0 * 1024.0));
    if (d.map->bytes_cap > 0) s += fmt(" of %.0f MiB cap", double(d.map->bytes_cap) / (1024.0 * 1024.0));
    s += fmt(", %.0f voxels, %.0f visual points", double(d.map->local_voxels), double(d.map->visual_points)) + "\n";
  }
  s += fmt("drawn %.0f map points (voxel %.2f m", double(d.map_points), d.voxel_m) +
       (d.map_evicted ? fmt(", %.0f evicted", double(d.map_evicted)) : "") + fmt("), scan %.0f", double(d.scan_points)) +
       "\n";
  if (d.keyframes > 0)
    s += fmt("loop closure: %.0f keyframes, %.0f loops", double(d.keyframes), double(d.loops)) +
         (d.corrections_refused ? fmt(", %.0f corrections refused", double(d.corrections_refused)) : "") + "\n";
  s += fmt("dropped: %.0f scans, %.0f images, %.0f rejected", double(d.drops.scans), double(d.drops.images),
           double(d.drops.rejected)) +
       "\n";
  s += "view " + viewModeName(d.view) + " (v)   colour " + colourModeName(d.colour) +
       " (b)   n reset   k screenshot   q quit";
  return s;
}

Scene::Scene(const SceneConfig& cfg) : cfg_(cfg), map_(cfg.map), track_(cfg.max_poses) {}

void Scene::apply(InboxBatch batch) {
  for (const ScanInput& s : batch.scans) map_.add(s.points, s.intensity, s.rgb);
  if (!batch.scans.empty()) {
    scan_ = std::move(batch.scans.back());
    ++scan_version_;
  }
  for (const PoseInput& p : batch.poses) {
    if (!track_.add(p)) continue;
    if (!first_utime_) first_utime_ = p.utime;
    recent_.push_back(p.utime);
    while (!recent_.empty() && toSeconds(p.utime - recent_.front()) > kRateWindowS) recent_.pop_front();
  }
  if (!batch.frame_stats.empty()) frame_ = batch.frame_stats.back();
  if (batch.map_stats) map_stats_ = batch.map_stats;
  for (const MapCorrection& c : batch.corrections) {
    if (!map_frame_.apply(c).empty()) ++corrections_refused_;  // another run's keyframes
    ++map_frame_version_;
  }
  drops_ = batch.drops;
}

std::vector<Vec3> Scene::mapFramePath() const {
  std::vector<Vec3> out;
  out.reserve(map_frame_.keyframes().size());
  for (const auto& [i, k] : map_frame_.keyframes()) out.push_back(k.T_map.translation());
  return out;
}

std::vector<std::pair<Vec3, Vec3>> Scene::loopEdges() const {
  std::vector<std::pair<Vec3, Vec3>> out;
  const auto& k = map_frame_.keyframes();
  for (const auto& [a, b] : map_frame_.loops()) {
    const auto ia = k.find(a), ib = k.find(b);
    if (ia != k.end() && ib != k.end()) out.emplace_back(ia->second.T_map.translation(), ib->second.T_map.translation());
  }
  return out;
}

void Scene::addMapPoints(const ScanInput& points) { map_.add(points.points, points.intensity, points.rgb); }

void Scene::clear() {
  map_.clear();
  track_.clear();
  scan_ = ScanInput{};
  ++scan_version_;
  frame_.reset();
  map_stats_.reset();
  first_utime_.reset();
  recent_.clear();
  map_frame_ = MapFrameTrajectory{};
  corrections_refused_ = 0;
  ++map_frame_version_;
}

std::optional<Utime> Scene::lastUtime() const {
  if (track_.empty()) return std::nullopt;
  return track_.last().utime;
}

double Scene::elapsedS() const {
  if (!first_utime_ || track_.empty()) return 0.0;
  return toSeconds(track_.last().utime - *first_utime_);
}

double Scene::rateHz() const {
  if (recent_.size() < 2) return 0.0;
  const double span = toSeconds(recent_.back() - recent_.front());
  return span > 0.0 ? double(recent_.size() - 1) / span : 0.0;
}

double Scene::clipZ() const {
  if (cfg_.clip_above_m <= 0.0 || track_.empty()) return std::numeric_limits<double>::infinity();
  return track_.maxCorner().z() + cfg_.clip_above_m;
}

ColouredPoints Scene::mapPoints(ColourMode mode) const {
  const float clip = static_cast<float>(std::min(clipZ(), double(std::numeric_limits<float>::max())));
  ColouredPoints out;
  out.xyz.reserve(map_.size());
  std::vector<float> value;  // height or intensity of each drawn point
  std::vector<std::int32_t> rgb;
  value.reserve(map_.size());
  map_.forEach([&](const MapPoint& m) {
    if (m.p.z() > clip) return;
    out.xyz.push_back(m.p);
    value.push_back(mode == ColourMode::kIntensity ? m.intensity : m.p.z());
    if (mode == ColourMode::kImage) rgb.push_back(m.rgb);
  });
  out.rgb.reserve(out.xyz.size());
  if (mode == ColourMode::kImage) {
    for (const std::int32_t c : rgb) out.rgb.push_back(imageColour(c));
    return out;
  }
  const float lo = mode == ColourMode::kIntensity ? 0.f : quantile(value, 0.01);
  const float hi = quantile(value, 0.99);
  const float span = hi - lo > 1e-6f ? hi - lo : 1.f;
  for (const float v : value) {
    const double t = double(v - lo) / double(span);
    out.rgb.push_back(mode == ColourMode::kIntensity ? intensityColour(t) : heightColour(t));
  }
  return out;
}

ColouredPoints Scene::scanPoints() const {
  const double clip = clipZ();
  ColouredPoints out;
  for (const Eigen::Vector3f& p : scan_.points)
    if (p.allFinite() && double(p.z()) <= clip) {
      out.xyz.push_back(p);
      out.rgb.push_back(kScanColour);
    }
  return out;
}

OverlayData Scene::overlay(const std::string& source, ViewMode view, ColourMode colour) const {
  OverlayData d;
  d.source = source;
  d.frames = track_.added();
  d.rate_hz = rateHz();
  d.t_s = elapsedS();
  d.frame = frame_;
  d.map = map_stats_;
  d.map_points = map_.size();
  d.scan_points = scan_.points.size();
  d.voxel_m = map_.config().voxel_m;
  d.map_evicted = map_.evicted();
  d.keyframes = map_frame_.known();
  d.loops = map_frame_.loops().size();
  d.corrections_refused = corrections_refused_;
  d.drops = drops_;
  d.view = view;
  d.colour = colour;
  return d;
}

}  // namespace livo::viewer
