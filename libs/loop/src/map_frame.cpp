#include "livo/loop/map_frame.hpp"

namespace livo {

std::string MapFrameTrajectory::apply(const MapCorrection& c) {
  for (std::size_t i = 0; i < c.keyframes.size(); ++i) {
    const auto it = keyframes_.find(c.first + std::int32_t(i));
    if (it != keyframes_.end() && it->second.utime != c.keyframes[i].utime)
      return "keyframe " + std::to_string(c.first + std::int64_t(i)) + " was at utime " +
             std::to_string(it->second.utime) + ", now at " + std::to_string(c.keyframes[i].utime) +
             " (another loop closer or run?)";
  }
  for (std::size_t i = 0; i < c.keyframes.size(); ++i) {
    const KeyframePose& k = c.keyframes[i];
    keyframes_[c.first + std::int32_t(i)] = k;
    carry_[k.utime] = k.T_map * k.T_odom.inverse();
  }
  if (c.loops.size() >= loops_.size()) loops_ = c.loops;
  total_ = std::max(total_, c.keyframes_total);
  final_ = final_ || c.final;
  return {};
}

std::optional<Pose> MapFrameTrajectory::toMap(Utime t, const Pose& T_odom) const {
  auto it = carry_.upper_bound(t);
  if (it == carry_.begin()) return std::nullopt;
  return std::prev(it)->second * T_odom;
}

}  // namespace livo
