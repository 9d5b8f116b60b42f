// A run's output directory for `livo-viewer --run DIR`: trajectory.tum (required) and map.pcd
// (optional: `livo-run --no-maps` writes none). Errors name the file and what is wrong.
#pragma once

#include "livo/viewer/inputs.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace livo::viewer {

struct RunDirectory {
  std::vector<PoseInput> poses;  ///< trajectory.tum, in time order
  ScanInput map;                 ///< map.pcd's points; rgb filled when the file has colours
  bool has_map = false;          ///< map.pcd was there
  std::string map_note;          ///< e.g. "map.pcd: 48,213 points (x y z rgb)" or why there is none
};

/// Reads DIR/trajectory.tum and DIR/map.pcd. Throws std::runtime_error naming the file: directory
/// missing, trajectory.tum missing or malformed (line named), map.pcd unreadable or without x, y, z.
RunDirectory loadRunDirectory(const std::string& dir);

/// Reads a PCD file's points (x y z, rgb or rgba when present); throws std::runtime_error naming
/// the file when PCL cannot read it or it has no x / y / z fields.
ScanInput loadPcdPoints(const std::string& path, std::string* fields = nullptr);

}  // namespace livo::viewer
