// The map RViz shows: the registered scans kept as one point per voxel (the first seen). Memory is
// bounded: when the map holds more than `max_points`, the voxel size doubles and the map is thinned to it.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

namespace livo_bridge {

class DecimatedMap {
 public:
  DecimatedMap(double voxel_m, std::int64_t max_points);
  /// Adds points (world frame); rgb may be null (no colour: -1).
  void add(std::size_t n, const float* x, const float* y, const float* z, const float* intensity,
           const std::int32_t* rgb);
  std::size_t size() const { return x_.size(); }
  double voxel() const { return voxel_; }
  bool coloured() const { return coloured_; }
  const std::vector<float>& x() const { return x_; }
  const std::vector<float>& y() const { return y_; }
  const std::vector<float>& z() const { return z_; }
  const std::vector<float>& intensity() const { return intensity_; }
  const std::vector<std::int32_t>& rgb() const { return rgb_; }

 private:
  std::uint64_t key(float x, float y, float z) const;
  void coarsen();
  double voxel_;
  std::int64_t max_points_;
  bool coloured_ = false;
  std::unordered_map<std::uint64_t, std::uint32_t> index_;
  std::vector<float> x_, y_, z_, intensity_;
  std::vector<std::int32_t> rgb_;
};

}  // namespace livo_bridge
