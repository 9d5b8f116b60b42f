// The drawn trajectory: poses in time order, bounded. When full, every second pose of the older half is
// dropped, so that the whole path stays visible at a coarser spacing where it is old.
#pragma once

#include "livo/viewer/inputs.hpp"

#include <cstddef>
#include <vector>

namespace livo::viewer {

class TrajectoryTrack {
 public:
  /// max_poses >= 4 (std::invalid_argument otherwise).
  explicit TrajectoryTrack(std::size_t max_poses = 200'000);

  /// Appends a pose; a pose not newer than the last one is ignored (returns false, counted).
  bool add(const PoseInput& pose);
  void clear();

  const std::vector<PoseInput>& poses() const { return poses_; }
  bool empty() const { return poses_.empty(); }
  const PoseInput& last() const { return poses_.back(); }
  std::uint64_t version() const { return version_; }
  std::uint64_t outOfOrder() const { return out_of_order_; }
  /// Poses added since the start or the last clear() (decimated ones included).
  std::uint64_t added() const { return added_; }
  /// Smallest and largest position of the drawn poses (zero when empty).
  Eigen::Vector3d minCorner() const { return lo_; }
  Eigen::Vector3d maxCorner() const { return hi_; }

 private:
  std::size_t max_poses_;
  std::vector<PoseInput> poses_;
  std::uint64_t version_ = 0, out_of_order_ = 0, added_ = 0;
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero(), hi_ = Eigen::Vector3d::Zero();
};

}  // namespace livo::viewer
