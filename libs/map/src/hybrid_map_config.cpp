#include "livo/map/hybrid_map_config.hpp"

#include <functional>
#include <stdexcept>

namespace livo {

namespace {

// Calls bad(key, what) for the first invalid field; one list shared by load() and validate().
void checkFields(const HybridMapConfig& c, const std::function<void(const char*, const char*)>& bad) {
  auto check = [&](bool ok, const char* key, const char* what) {
    if (!ok) bad(key, what);
  };
  check(c.local_edge_m > 0.0 && c.local_edge_m < 1e6, "local_edge_m", "must be in (0, 1e6) m");
  check(c.slide_distance_m > 0.0 && c.slide_distance_m < 0.5 * c.local_edge_m, "slide_distance_m",
        "must be in (0, local_edge_m / 2) m");
  check(c.longterm_edge_m >= c.local_edge_m && c.longterm_edge_m < 1e7, "longterm_edge_m",
        "must be >= local_edge_m and < 1e7 m");
  check(c.longterm_slide_m > 0.0 && c.longterm_slide_m < 0.5 * c.longterm_edge_m, "longterm_slide_m",
        "must be in (0, longterm_edge_m / 2) m");
  check(c.memory_cap_mb >= 0.0 && c.memory_cap_mb < 1e7, "memory_cap_mb", "must be in [0, 1e7) MiB (0 = no cap)");
  check(c.cap_high_water > 0.0 && c.cap_high_water <= 1.0, "cap_high_water", "must be in (0, 1]");
  check(c.cap_low_water > 0.0 && c.cap_low_water < c.cap_high_water, "cap_low_water",
        "must be in (0, cap_high_water)");
  check(c.recount_interval >= 1, "recount_interval", "must be >= 1");
  check(c.longterm_points_per_voxel >= 0, "longterm_points_per_voxel", "must be >= 0 (0 = no limit)");
  check(c.longterm_min_observations >= 1 && c.longterm_min_observations <= 1000, "longterm_min_observations",
        "must be in [1, 1000]");
  check(c.tile_edge_m > 0.0 && c.tile_edge_m < 1e4, "tile_edge_m", "must be in (0, 1e4) m");
  check(c.max_removals_per_update >= 0, "max_removals_per_update", "must be >= 0 (0 = unlimited)");
}

}  // namespace

void HybridMapConfig::load(const ConfigNode& node) {
  node.get("local_edge_m", local_edge_m);
  node.get("slide_distance_m", slide_distance_m);
  node.get("longterm_enabled", longterm_enabled);
  node.get("longterm_edge_m", longterm_edge_m);
  node.get("longterm_slide_m", longterm_slide_m);
  node.get("longterm_reference_only", longterm_reference_only);
  node.get("longterm_points_per_voxel", longterm_points_per_voxel);
  node.get("longterm_min_observations", longterm_min_observations);
  node.get("memory_cap_mb", memory_cap_mb);
  node.get("cap_high_water", cap_high_water);
  node.get("cap_low_water", cap_low_water);
  node.get("recount_interval", recount_interval);
  node.get("tile_edge_m", tile_edge_m);
  node.get("max_removals_per_update", max_removals_per_update);
  checkFields(*this, [&](const char* key, const char* what) { node.fail(key, what); });
}

void HybridMapConfig::validate() const {
  checkFields(*this, [](const char* key, const char* what) {
    throw std::invalid_argument(std::string("HybridMapConfig: ") + key + " " + what);
  });
}

}  // namespace livo
