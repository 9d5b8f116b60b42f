// Parametric world generators (world.kind), all with the floor at z = 0 and z up:
// - room: box size_m = [x, y, z] centred on the origin (walls, floor, ceiling as 0.2 m slabs) furnished
//   with crates, tables, cabinets, pillars, leaning panels, wall frames and ceiling lamps
//   (clutter 0..1 sets how many), several plane orientations.
// - corridor: [length, width, height] along x, centred on the origin, open at both ends (no end caps,
//   so it is LiDAR-degenerate along x), uniform cross-section, never cluttered.
// - street: ground plus buildings (boxes, some stepped) on both sides of the trajectory's loop, and
//   poles, parked cars and trees (clutter); size_m.z is the tallest building.
// - wall: one wall of [_, width, height] with its face at x = size_m.x, centred at z = 1.4 m.
// Obstacles keep clear of the trajectory's path (given as a polyline).
#pragma once

#include "livo/sim/scenario.hpp"
#include "livo/sim/world.hpp"

#include <vector>

namespace livo::sim {

/// Builds the world of a scenario around `path`. Throws std::runtime_error on unreadable texture images.
World makeWorld(const SimScenario& scenario, const std::vector<Vec3>& path);

/// Texture image paths of a scenario resolved against its folder (absolute paths stay as they are).
std::vector<std::string> resolveTexturePaths(const SimScenario& scenario);

}  // namespace livo::sim
