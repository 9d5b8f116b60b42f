// Core of livo-mapserver: owns the hybrid map (MapService, livo/map/map_service.hpp); LIVO_MAP_QUERY
// in -> LIVO_SUBMAP out, LIVO_MAP_UPDATE in, LIVO_MAP_STATS out once per second of message time (and
// at the end). Messages are handled in arrival order, so an update sent before the next query is in
// the map when that query is answered.
#pragma once

#include "livo/io/channels.hpp"
#include "livo/map/map_service.hpp"

#include <livo/map_query_t.hpp>
#include <livo/map_update_t.hpp>
#include "livo/process/lcm_node.hpp"

#include <cstdint>
#include <ostream>
#include <string>

namespace livo {

class MapServerNode {
 public:
  MapServerNode(LcmNode& lcm, MapService& service, const ChannelConfig& channels, std::ostream* log,
                double stats_interval_s = 1.0);
  /// Publishes LIVO_MAP_STATS now (exact counts).
  void publishStats();

  struct Counters {
    std::uint64_t submaps_published = 0, submap_bytes = 0, max_submap_bytes = 0;
    std::uint64_t max_submap_planes = 0, max_submap_visual_points = 0;
    std::uint64_t stats_published = 0;
    std::uint64_t worst_update_utime = 0;
  };
  const Counters& counters() const { return counters_; }
  std::string progressLine() const;
  std::string summary() const;

 private:
  Validation onQuery(const livo::map_query_t& m);
  Validation onUpdate(const livo::map_update_t& m);
  void maybeStats(Utime t);

  LcmNode& lcm_;
  MapService& service_;
  ChannelConfig channels_;
  std::ostream* log_;
  double stats_interval_s_;
  bool have_stats_time_ = false;
  Utime last_stats_utime_ = 0;
  Counters counters_;
};

}  // namespace livo
