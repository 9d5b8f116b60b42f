#include "livo/viewer/trajectory_track.hpp"

#include <stdexcept>

namespace livo::viewer {

TrajectoryTrack::TrajectoryTrack(std::size_t max_poses) : max_poses_(max_poses) {
  if (max_poses_ < 4) throw std::invalid_argument("TrajectoryTrack: max_poses must be >= 4");
}

bool TrajectoryTrack::add(const PoseInput& pose) {
  if (!poses_.empty() && pose.utime <= poses_.back().utime) {
    ++out_of_order_;
    return false;
  }
  if (poses_.size() >= max_poses_) {
    // Keep the first pose and every second one of the older half; the newer half stays whole.
    const std::size_t half = poses_.size() / 2;
    std::vector<PoseInput> kept;
    kept.reserve(max_poses_);
    for (std::size_t i = 0; i < half; i += 2) kept.push_back(poses_[i]);
    kept.insert(kept.end(), poses_.begin() + static_cast<std::ptrdiff_t>(half), poses_.end());
    poses_.swap(kept);
  }
  const Eigen::Vector3d p = pose.T_world_imu.translation();
  if (poses_.empty()) lo_ = hi_ = p;
  lo_ = lo_.cwiseMin(p);
  hi_ = hi_.cwiseMax(p);
  poses_.push_back(pose);
  ++added_;
  ++version_;
  return true;
}

void TrajectoryTrack::clear() {
  poses_.clear();
  lo_ = hi_ = Eigen::Vector3d::Zero();
  added_ = 0;
  ++version_;
}

}  // namespace livo::viewer
