// ByteAccounting: the exact count, the O(1) estimate and its calibration.
#include "livo/map/byte_accounting.hpp"

#include "livo/map/dual_visual_map.hpp"
#include "livo/map/local_lidar_map.hpp"

#include <algorithm>

namespace livo {

// Defaults until the first exact count (1300 B per root voxel incl. index: the simulated street with a
// spinning 32-ring LiDAR, 0.5 m voxels).
ByteAccounting::ByteAccounting()
    : bytes_per_root_(1300.0),
      bytes_per_local_point_(double(sizeof(VisualPoint) + 4 * sizeof(VisualObservation) + 128)),
      bytes_per_longterm_point_(double(sizeof(VisualPoint) + sizeof(VisualObservation) + 128)) {}

HybridMapStats ByteAccounting::count(const LocalLidarMap& lidar, const DualVisualMap& visual, std::size_t work_bytes) {
  HybridMapStats s;
  s.local_voxels = lidar.voxels().numRootVoxels();
  s.visual_points_local = visual.local().size();
  s.visual_points_longterm = visual.longterm().size();
  s.bytes_lidar = lidar.voxels().bytes();
  s.bytes_visual_local = visual.local().bytes() + visual.local().scratchBytes();
  s.bytes_visual_longterm = visual.longterm().bytes() + visual.longterm().scratchBytes();
  s.bytes_index = lidar.tiles().bytes() + work_bytes;
  s.bytes = s.bytes_lidar + s.bytes_visual_local + s.bytes_visual_longterm + s.bytes_index;
  return s;
}

std::size_t ByteAccounting::estimate(const LocalLidarMap& lidar, const DualVisualMap& visual) const {
  const std::size_t points = lidar.insertedPoints() - points_at_count_;
  const std::size_t observations = visual.addedObservations() - observations_at_count_;
  const double b = bytes_per_root_ * double(lidar.voxels().numRootVoxels()) +
                   bytes_per_local_point_ * double(visual.local().size()) +
                   bytes_per_longterm_point_ * double(visual.longterm().size()) + double(fixed_bytes_) +
                   growth_per_point_ * double(points) + double(observations * sizeof(VisualObservation));
  return static_cast<std::size_t>(b);
}

std::size_t ByteAccounting::recount(const LocalLidarMap& lidar, const DualVisualMap& visual, std::size_t work_bytes) {
  const HybridMapStats s = count(lidar, visual, work_bytes);
  // Growth inside existing root voxels (points collecting in leaves) is not in the per-root ratio:
  // learn it per inserted LiDAR point from what the estimate missed (smoothed, never negative).
  const std::size_t points = lidar.insertedPoints() - points_at_count_;
  if (points > 0) {
    const double missed = double(s.bytes) - double(estimate(lidar, visual));
    const double rate = std::max(0.0, missed) / double(points);
    growth_per_point_ = counted_ ? 0.5 * (growth_per_point_ + rate) : rate;
  }
  points_at_count_ = lidar.insertedPoints();
  observations_at_count_ = visual.addedObservations();
  // Bytes per item, without the scratch buffers (fixed); the index goes with the roots.
  const std::size_t local_scratch = visual.local().scratchBytes();
  const std::size_t longterm_scratch = visual.longterm().scratchBytes();
  fixed_bytes_ = local_scratch + longterm_scratch;
  if (s.local_voxels > 0) bytes_per_root_ = double(s.bytes_lidar + s.bytes_index) / double(s.local_voxels);
  else fixed_bytes_ += s.bytes_lidar + s.bytes_index;
  if (s.visual_points_local > 0)
    bytes_per_local_point_ = double(s.bytes_visual_local - local_scratch) / double(s.visual_points_local);
  else fixed_bytes_ += s.bytes_visual_local - local_scratch;
  if (s.visual_points_longterm > 0)
    bytes_per_longterm_point_ = double(s.bytes_visual_longterm - longterm_scratch) / double(s.visual_points_longterm);
  else fixed_bytes_ += s.bytes_visual_longterm - longterm_scratch;
  counted_ = true;
  return s.bytes;
}

}  // namespace livo
