#include "livo/process/mapserver_node.hpp"

#include "livo/common/timing.hpp"
#include "livo/io/map_messages.hpp"

#include <algorithm>
#include <iomanip>
#include <sstream>

namespace livo {

MapServerNode::MapServerNode(LcmNode& lcm, MapService& service, const ChannelConfig& channels, std::ostream* log,
                             double stats_interval_s, std::size_t max_resume_imu)
    : lcm_(lcm), service_(service), channels_(channels), log_(log), stats_interval_s_(stats_interval_s),
      max_resume_imu_(std::max<std::size_t>(1, max_resume_imu)) {
  lcm_.subscribe<livo::map_query_t>(channels_.map_query, [this](const livo::map_query_t& m) { return onQuery(m); });
  lcm_.subscribe<livo::map_update_t>(channels_.map_update, [this](const livo::map_update_t& m) { return onUpdate(m); });
  lcm_.subscribe<livo::filter_state_t>(channels_.filter_state,
                                       [this](const livo::filter_state_t& m) { return onFilterState(m); });
  lcm_.subscribe<livo::imu_t>(channels_.imu, [this](const livo::imu_t& m) { return onImu(m); });
  lcm_.subscribe<livo::resume_request_t>(channels_.resume_request,
                                         [this](const livo::resume_request_t& m) { return onResumeRequest(m); });
}

Validation MapServerNode::onFilterState(const livo::filter_state_t& m) {
  FilterSnapshot s;
  Validation v = fromMsg(m, s);
  if (!v) return v;
  last_state_ = std::move(s);
  have_state_ = true;
  ++counters_.filter_states;
  const Utime t = last_state_.filter.state.utime;
  while (!imu_since_.empty() && imu_since_.front().utime <= t) imu_since_.pop_front();
  imu_dropped_since_ = 0;
  return Validation::ok();
}

Validation MapServerNode::onImu(const livo::imu_t& m) {
  ImuSample s;
  Validation v = fromMsg(m, s);
  if (!v) return v;
  if (have_state_ && s.utime <= last_state_.filter.state.utime) return Validation::ok();  // covered by the state
  if (!imu_since_.empty() && s.utime <= imu_since_.back().utime) {
    // Far back: a new log (start again); else a duplicate or a sample out of order (left out).
    if (toSeconds(imu_since_.back().utime - s.utime) > 1.0) imu_since_.clear();
    else return Validation::ok();
  }
  if (imu_since_.size() >= max_resume_imu_) {
    imu_since_.pop_front();
    if (have_state_) {
      ++imu_dropped_since_;
      ++counters_.resume_imu_dropped;
    }
  }
  imu_since_.push_back(s);
  return Validation::ok();
}

Validation MapServerNode::onResumeRequest(const livo::resume_request_t& m) {
  ResumeAnswer a;
  a.request_id = m.request_id;
  a.have_state = have_state_;
  if (!config_lines_.empty() && !m.config.empty()) {
    // "here" is the estimator's side in the message it reads.
    for (const std::string& d : configDifferences(m.config, config_lines_, {"map.memory_cap_mb"}))
      a.config_mismatch += (a.config_mismatch.empty() ? "" : "; ") + d;
    if (!a.config_mismatch.empty() && log_)
      *log_ << "livo-mapserver: error: an estimator with another config asked to resume: " << a.config_mismatch << "\n";
  }
  if (have_state_) {
    a.snapshot = last_state_;
    a.imu.assign(imu_since_.begin(), imu_since_.end());
    a.imu_dropped = std::int64_t(imu_dropped_since_);
  }
  lcm_.publish(channels_.resume, toMsg(a));
  ++counters_.resume_answers;
  if (have_state_) ++counters_.resume_with_state;
  if (log_) {
    *log_ << "livo-mapserver: an estimator asked for the last filter state: ";
    if (have_state_)
      *log_ << "sent the state of t " << toSeconds(last_state_.filter.state.utime) << " s with " << a.imu.size()
            << " IMU samples after it\n";
    else
      *log_ << "none yet (a new run)\n";
  }
  return Validation::ok();
}

void MapServerNode::setPriorMap(PriorMapSeeder* seeder) {
  prior_ = seeder;
  if (!prior_) return;
  lcm_.subscribeStruct<livo::map_correction_t, MapCorrection>(channels_.map_correction, [this](MapCorrection& c) {
    ++counters_.map_corrections;
    if (c.keyframes_total == 0) return;  // not localised yet
    if (!have_correction_ && log_) *log_ << "livo-mapserver: localised in the site map: serving its planes\n";
    have_correction_ = true;
    T_map_odom_ = c.T_map_odom;
  });
}

Validation MapServerNode::onQuery(const livo::map_query_t& m) {
  MapQuery q;
  Validation v = fromMsg(m, q, lcm_.limits());
  if (!v) return v;
  if (prior_ && have_correction_) {
    const std::vector<PointWithCov> pts = prior_->pointsNear(T_map_odom_, q.T_world_imu.translation());
    if (!pts.empty()) {
      service_.map().lidar().insert(pts);
      counters_.prior_points += pts.size();
    }
  }
  const Submap s = service_.answer(q);
  const livo::submap_t out = toMsg(s);
  const auto bytes = std::uint64_t(out.getEncodedSize());
  lcm_.publish(channels_.submap, out);
  ++counters_.submaps_published;
  counters_.submap_bytes += bytes;
  counters_.max_submap_bytes = std::max(counters_.max_submap_bytes, bytes);
  counters_.max_submap_planes = std::max<std::uint64_t>(counters_.max_submap_planes, s.planes.size());
  counters_.max_submap_visual_points =
      std::max<std::uint64_t>(counters_.max_submap_visual_points, s.visual_points.size());
  maybeStats(q.utime);
  return Validation::ok();
}

Validation MapServerNode::onUpdate(const livo::map_update_t& m) {
  MapUpdate u;
  Validation v = fromMsg(m, u, lcm_.limits());
  if (!v) return v;
  const double worst_before = service_.counters().max_update_ms;
  const MapUpdateReport rep = service_.apply(u);
  if (service_.counters().max_update_ms > worst_before) counters_.worst_update_utime = std::uint64_t(u.utime);
  if (log_ && (rep.evicted_longterm_points + rep.evicted_local_points + rep.evicted_local_voxels) > 0 &&
      shouldWarn(service_.map().counters().eviction_events))
    *log_ << "livo-mapserver: memory cap: evicted " << rep.evicted_longterm_points << " long-term and "
          << rep.evicted_local_points << " local visual points, " << rep.evicted_local_voxels
          << " voxels (map now ~" << rep.bytes / (1 << 20) << " MiB)\n";
  maybeStats(u.utime);
  return Validation::ok();
}

void MapServerNode::maybeStats(Utime t) {
  if (stats_interval_s_ <= 0) return;
  if (!have_stats_time_) {
    have_stats_time_ = true;
    last_stats_utime_ = t;
    return;
  }
  if (t < last_stats_utime_) last_stats_utime_ = t;  // time jumped back (new log): restart the clock
  if (toSeconds(t - last_stats_utime_) < stats_interval_s_) return;
  last_stats_utime_ = t;
  publishStats();
}

void MapServerNode::publishStats() {
  lcm_.publish(channels_.map_stats, toMsg(service_.stats()));
  ++counters_.stats_published;
}

std::string MapServerNode::progressLine() const {
  const MapServiceCounters& c = service_.counters();
  std::ostringstream os;
  os << std::fixed << std::setprecision(3) << "t " << toSeconds(service_.latestTime()) << " s: queries " << c.queries
     << " (visual " << c.visual_queries << "), updates " << c.updates << ", map ~"
     << service_.map().bytesEstimate() / (1 << 20) << " MiB, rejected " << lcm_.totalRejected();
  return os.str();
}

std::string MapServerNode::summary() const {
  const MapServiceCounters& c = service_.counters();
  const HybridMapCounters& h = service_.map().counters();
  const MapStats s = service_.stats();
  std::ostringstream os;
  os << std::fixed << std::setprecision(2);
  os << "queries " << c.queries << " (visual " << c.visual_queries << "), updates " << c.updates << " (stale "
     << c.stale_updates << "), points inserted " << c.points_inserted << "\n";
  if (prior_)
    os << "site map: " << counters_.map_corrections << " corrections, " << prior_->keyframesHanded()
       << " keyframes (" << counters_.prior_points << " points) served"
       << (have_correction_ ? "" : "; never localised (is livo-loop --prior-map running?)") << "\n";
  os << "visual points: upserts " << c.visual_upserts << ", removals " << c.visual_removals << ", rejected "
     << c.visual_rejected << ", observations " << c.observations_added << " (unknown ids " << c.observations_unknown
     << ")\n";
  os << "submaps: " << counters_.submaps_published << ", mean bytes "
     << double(counters_.submap_bytes) / std::max<double>(1.0, double(counters_.submaps_published)) << ", max bytes "
     << counters_.max_submap_bytes << ", max planes " << counters_.max_submap_planes << ", max visual points "
     << counters_.max_submap_visual_points << "\n";
  os << "map: voxels " << s.local_voxels << ", planes " << s.local_planes << ", visual points local "
     << s.visual_points_local << " long-term " << s.visual_points_longterm << ", bytes " << s.bytes << " (cap "
     << s.bytes_cap << ")\n";
  os << "slides " << h.slides << " (worst " << h.max_slide_ms << " ms), evicted: voxels " << h.evicted_local_voxels
     << ", visual points " << h.evicted_longterm_points + h.evicted_local_points << "; worst update "
     << c.max_update_ms << " ms at t " << toSeconds(Utime(counters_.worst_update_utime)) << " s (CPU time: worst "
     << c.max_update_cpu_ms << " ms, median " << c.update_cpu_ms.quantile(0.5) << ", p99 " << c.update_cpu_ms.quantile(0.99)
     << " ms; worst parts: insertion " << c.max_insert_cpu_ms << ", visual " << c.max_visual_cpu_ms
     << ", maintenance " << c.max_maintenance_cpu_ms << " ms)\n";
  os << "estimator restarts: filter states " << counters_.filter_states << ", resume answers " << counters_.resume_answers
     << " (with a state " << counters_.resume_with_state << "), IMU samples dropped from the buffer "
     << counters_.resume_imu_dropped << "\n";
  os << resourceSummary() << "\n";
  os << "messages:\n" << lcm_.countersSummary();
  return os.str();
}

}  // namespace livo
