// Map files of livo-mapserver --map-file: the hybrid map's content (LiDAR voxel octrees with their
// planes and points, local and long-term visual points with their patches) in a versioned binary
// format, so that a restarted map server continues with the map of the previous run.
//
// Layout (little-endian, as written by x86-64 / arm64): "LIVOMAP1", u32 version, f64 root voxel
// size, f64 visual voxel size, then the LiDAR map (u64 root count, per root 3 x i64 key + octree
// nodes depth first) and the two visual maps (u64 count, per point its fields and observations).
// Every count is checked against the remaining limits before anything is allocated; a file written
// with other voxel sizes is refused (its keys would not match). Counters, cube centres and pending
// slide work are not saved: the first update() after loading centres the cubes at the robot again.
#pragma once

#include "livo/map/hybrid_map.hpp"

#include <cstddef>
#include <istream>
#include <ostream>
#include <string>

namespace livo {

struct MapFileInfo {
  std::size_t root_voxels = 0;
  std::size_t planes = 0;
  std::size_t visual_points_local = 0;
  std::size_t visual_points_longterm = 0;
  std::size_t file_bytes = 0;
  std::string describe() const;  ///< "1234 voxels, 2000 planes, 300 + 50 visual points, 12.3 MB"
};

/// Writes the map to `path` (through a temporary file renamed at the end, so a crash never leaves a
/// half-written map). Throws std::runtime_error naming the path on I/O errors.
MapFileInfo saveMap(const std::string& path, const HybridMap& map);
/// Replaces the map's content with the file's. Throws std::runtime_error naming the path and the
/// problem (not a map file, version, voxel size mismatch, truncated, bad count); the map is then empty.
MapFileInfo loadMap(const std::string& path, HybridMap& map);
/// The same on streams (`name` stands for the file in errors; file_bytes stays 0).
MapFileInfo saveMap(std::ostream& os, const HybridMap& map);
MapFileInfo loadMap(std::istream& is, const std::string& name, HybridMap& map);

}  // namespace livo
