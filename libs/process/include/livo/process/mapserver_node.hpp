// Core of livo-mapserver: owns the hybrid map (MapService, livo/map/map_service.hpp); LIVO_MAP_QUERY
// in -> LIVO_SUBMAP out, LIVO_MAP_UPDATE in, LIVO_MAP_STATS out once per second of message time (and
// at the end). Messages are handled in arrival order, so an update sent before the next query is in
// the map when that query is answered.
//
// Restarts of the estimator: the node keeps the latest LIVO_FILTER_STATE and the LIVO_IMU samples after
// it (at most `max_resume_imu`, the oldest dropped and counted), and answers LIVO_RESUME_REQUEST with
// both on LIVO_RESUME (livo/io/resume_messages.hpp; estimator_node.hpp says what the estimator does).
//
// With a site map (livo-mapserver --prior-map, setPriorMap): the node follows LIVO_MAP_CORRECTION (livo-loop
// --prior-map, which localises the odometry in that map) and, once a correction came, inserts the map's
// keyframes near each query's position into the LiDAR map before answering (PriorMapSeeder), so that the
// map's planes serve the estimator's LiDAR update.
#pragma once

#include "livo/io/channels.hpp"
#include "livo/map/map_service.hpp"

#include <livo/map_query_t.hpp>
#include <livo/map_update_t.hpp>
#include <livo/resume_request_t.hpp>
#include "livo/io/loop_messages.hpp"
#include "livo/io/resume_messages.hpp"
#include "livo/loop/prior_seeder.hpp"
#include "livo/process/lcm_node.hpp"

#include <cstdint>
#include <deque>
#include <ostream>
#include <string>

namespace livo {

class MapServerNode {
 public:
  MapServerNode(LcmNode& lcm, MapService& service, const ChannelConfig& channels, std::ostream* log,
                double stats_interval_s = 1.0, std::size_t max_resume_imu = 12000);
  /// Publishes LIVO_MAP_STATS now (exact counts).
  void publishStats();

  struct Counters {
    std::uint64_t submaps_published = 0, submap_bytes = 0, max_submap_bytes = 0;
    std::uint64_t max_submap_planes = 0, max_submap_visual_points = 0;
    std::uint64_t stats_published = 0;
    std::uint64_t worst_update_utime = 0;
    std::uint64_t filter_states = 0;      ///< LIVO_FILTER_STATE received (valid)
    std::uint64_t resume_answers = 0;     ///< LIVO_RESUME sent
    std::uint64_t resume_with_state = 0;  ///< ... of those with a state
    std::uint64_t resume_imu_dropped = 0; ///< IMU samples after the last state dropped (buffer full)
    std::uint64_t map_corrections = 0;    ///< LIVO_MAP_CORRECTION received (with a site map)
    std::uint64_t prior_points = 0;       ///< site map points inserted
  };
  const Counters& counters() const { return counters_; }
  /// The process's effective config (ConfigFile::effectiveLines()): a resume request whose config
  /// differs in a key both read (except map.memory_cap_mb, the map server's own) gets the differences.
  void setConfigLines(std::string lines) { config_lines_ = std::move(lines); }
  /// Serve a site map's planes once livo-loop has localised (see above); `seeder` must outlive the node.
  void setPriorMap(PriorMapSeeder* seeder);
  std::string progressLine() const;
  std::string summary() const;

 private:
  Validation onQuery(const livo::map_query_t& m);
  Validation onUpdate(const livo::map_update_t& m);
  void maybeStats(Utime t);
  Validation onFilterState(const livo::filter_state_t& m);
  Validation onImu(const livo::imu_t& m);
  Validation onResumeRequest(const livo::resume_request_t& m);

  LcmNode& lcm_;
  MapService& service_;
  ChannelConfig channels_;
  std::ostream* log_;
  double stats_interval_s_;
  bool have_stats_time_ = false;
  Utime last_stats_utime_ = 0;
  Counters counters_;
  // Resume support.
  std::size_t max_resume_imu_;
  bool have_state_ = false;
  FilterSnapshot last_state_;
  std::deque<ImuSample> imu_since_;  ///< samples after last_state_'s time (or the newest, before any state)
  std::uint64_t imu_dropped_since_ = 0;
  std::string config_lines_;
  // Site map.
  PriorMapSeeder* prior_ = nullptr;
  bool have_correction_ = false;
  Pose T_map_odom_ = Pose::Identity();
};

}  // namespace livo
