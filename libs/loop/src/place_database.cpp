#include "livo/loop/place_database.hpp"

#include <algorithm>
#include <cmath>

namespace livo {

void KeyframeConfig::load(const ConfigNode& loop) {
  loop.get("keyframe_distance_m", distance_m).get("keyframe_angle_deg", angle_deg);
  loop.check(std::isfinite(distance_m) && distance_m > 0 && distance_m <= 1000, "keyframe_distance_m",
             "must be in (0, 1000] m");
  loop.check(std::isfinite(angle_deg) && angle_deg > 0 && angle_deg <= 180, "keyframe_angle_deg",
             "must be in (0, 180] deg");
}

bool KeyframeSelector::offer(const Pose& T) {
  if (have_last_) path_m_ += (T.translation() - last_.translation()).norm();
  last_ = T;
  have_last_ = true;
  if (have_key_) {
    const double moved = (T.translation() - key_.translation()).norm();
    const double turned = rotationAngle(key_.linear().transpose() * T.linear());
    if (moved < cfg_.distance_m && turned < cfg_.angle_deg * M_PI / 180.0) return false;
  }
  key_ = T;
  have_key_ = true;
  return true;
}

void PlaceSearchConfig::load(const ConfigNode& loop, const PlaceDescriptorConfig& descriptor) {
  min_path_m = 2.0 * descriptor.max_range_m;
  loop.get("search_candidates", ring_candidates).get("match_distance", max_distance);
  loop.get("min_loop_path_m", min_path_m);
  loop.check(ring_candidates >= 1 && ring_candidates <= 1000, "search_candidates", "must be in [1, 1000]");
  loop.check(std::isfinite(max_distance) && max_distance > 0 && max_distance <= 1, "match_distance",
             "must be in (0, 1]");
  loop.check(std::isfinite(min_path_m) && min_path_m >= 0, "min_loop_path_m", "must be >= 0");
}

int PlaceDatabase::add(PlaceEntry e) {
  entries_.push_back(std::move(e));
  return static_cast<int>(entries_.size()) - 1;
}

std::vector<PlaceCandidate> PlaceDatabase::search(const PlaceDescriptor& query, double path_m) const {
  std::vector<PlaceCandidate> near;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const PlaceEntry& e = entries_[i];
    if (path_m - e.path_m < cfg_.min_path_m) continue;
    PlaceCandidate c;
    c.id = static_cast<int>(i);
    c.ring_key_distance = query.ringKeyDistance(e.descriptor);
    if (std::isfinite(c.ring_key_distance)) near.push_back(c);
  }
  const auto by_key = [](const PlaceCandidate& a, const PlaceCandidate& b) {
    return a.ring_key_distance < b.ring_key_distance || (a.ring_key_distance == b.ring_key_distance && a.id < b.id);
  };
  const auto keep = std::min(near.size(), static_cast<std::size_t>(cfg_.ring_candidates));
  std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(keep), near.end(), by_key);
  near.resize(keep);
  std::vector<PlaceCandidate> out;
  for (PlaceCandidate& c : near) {
    c.match = query.match(entries_[static_cast<std::size_t>(c.id)].descriptor);
    if (c.match.distance < cfg_.max_distance) out.push_back(c);
  }
  std::sort(out.begin(), out.end(), [](const PlaceCandidate& a, const PlaceCandidate& b) {
    return a.match.distance < b.match.distance || (a.match.distance == b.match.distance && a.id < b.id);
  });
  return out;
}

}  // namespace livo
