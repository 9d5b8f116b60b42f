// A LiDAR place signature: the points around a keyframe, in its gravity-aligned frame (z up, x along the
// keyframe's heading, origin at the sensor), binned into rings (range) x sectors (azimuth); each cell
// holds the height of its highest point above the scan's floor. A turn of the sensor about z shifts the
// sectors circularly, so two descriptors are compared at every circular shift and the best shift is the
// yaw between them. The ring key (each ring's mean cell) does not change under the shift: it is what the
// keyframe search compares first. docs/algorithms.md, "Place recognition".
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/so3.hpp"

#include <vector>

namespace livo {

struct PlaceDescriptorConfig {
  int rings = 20;            ///< loop.descriptor_rings: range bins over (min_range_m, max_range_m]
  int sectors = 60;          ///< loop.descriptor_sectors: azimuth bins over 360 deg (6 deg each)
  double min_range_m = 1.0;  ///< loop.descriptor_min_range_m: nearer points (the robot itself) are left out
  double max_range_m = 40.0; ///< loop.descriptor_range_m: farther points are left out
  double height_cap_m = 12.0;  ///< loop.descriptor_height_m: cell heights are clipped to this, then scaled to [0, 1]

  /// Reads the descriptor keys of the `loop` section; `lidar_max_range_m` (lidar.max_range_m) bounds the
  /// range: a descriptor cannot see farther than the sensor.
  void load(const ConfigNode& loop, double lidar_max_range_m);
};

/// The yaw between two descriptors: `yaw_rad` turns the candidate's points onto the query's
/// (p_query ~= Rz(yaw) p_candidate); `distance` in [0, 1] (0: the same place), 1 when too few sectors
/// hold points in both to compare.
struct PlaceMatch {
  double distance = 1.0;
  double yaw_rad = 0.0;
  int shift = 0;         ///< the best circular shift, sectors
  int compared = 0;      ///< sectors with points in both at that shift
};

class PlaceDescriptor {
 public:
  PlaceDescriptor() = default;
  /// Bins `points` (in the keyframe's gravity-aligned frame, see above).
  static PlaceDescriptor compute(const std::vector<Vec3>& points, const PlaceDescriptorConfig& cfg);
  /// The same from points in the odometry frame seen from `T_world_body` (in keyframeFrame(T_world_body):
  /// roll and pitch are not removed, the filter's frame is gravity-aligned).
  static PlaceDescriptor computeAt(const std::vector<Vec3>& world_points, const Pose& T_world_body,
                                   const PlaceDescriptorConfig& cfg);

  /// From stored cells (a saved site map): rings x sectors values in [0, 1], ring-major. Throws
  /// std::invalid_argument on a wrong count or value.
  static PlaceDescriptor fromCells(int rings, int sectors, std::vector<float> cells);
  const std::vector<float>& cells() const { return cells_; }
  int rings() const { return rings_; }
  int sectors() const { return sectors_; }
  bool empty() const { return cells_.empty(); }
  /// Scaled height of cell (ring, sector), 0 when the cell holds no point.
  float cell(int ring, int sector) const { return cells_[static_cast<std::size_t>(ring * sectors_ + sector)]; }
  /// Sectors holding at least one point.
  int occupiedSectors() const;

  /// L1 distance of the ring keys divided by the ring count (the search's first filter).
  double ringKeyDistance(const PlaceDescriptor& candidate) const;
  /// Compares at every circular shift (mean cosine distance of the sector columns that hold points in
  /// both) and refines the best shift to a fraction of a sector. Descriptors of different sizes: distance 1.
  PlaceMatch match(const PlaceDescriptor& candidate) const;

 private:
  int rings_ = 0;
  int sectors_ = 0;
  std::vector<float> cells_;     // ring-major
  std::vector<float> col_norm_;  // per sector, the norm of its column (0: empty)
  std::vector<float> ring_key_;  // per ring, the mean of its cells: invariant under a turn about z

  void summarise();  ///< ring keys and column norms from the cells
  double distanceAtShift(const PlaceDescriptor& candidate, int shift, int* compared) const;
};

/// The yaw of a pose's x axis about the world z axis, radians in (-pi, pi].
double yawOf(const Pose& T_world_body);
/// The keyframe frame of a body pose: the pose's position and heading (yawOf), no roll or pitch.
Pose keyframeFrame(const Pose& T_world_body);

}  // namespace livo
