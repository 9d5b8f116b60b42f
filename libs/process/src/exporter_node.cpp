#include "livo/process/exporter_node.hpp"

#include "livo/common/timing.hpp"
#include "livo/eval/tum.hpp"
#include "livo/io/frame_row.hpp"

#include <iomanip>
#include <sstream>

namespace livo {

ExporterNode::ExporterNode(LcmNode& lcm, const ChannelConfig& channels, const MapExportConfig& cfg,
                           const std::string& out_dir, std::ostream* log)
    : lcm_(lcm), channels_(channels), cfg_(cfg), log_(log), outputs_(out_dir, /*append=*/true), cloud_(cfg), occupancy_(cfg) {
  lcm_.subscribeStruct<livo::odometry_t, OdometryOutput>(channels_.odometry,
                                                          [this](OdometryOutput& o) { onOdometry(o); });
  lcm_.subscribeStruct<livo::estimator_stats_t, EstimatorStats>(channels_.estimator_stats,
                                                                 [this](EstimatorStats& s) { onStats(s); });
  lcm_.subscribeStruct<livo::registered_scan_t, RegisteredScan>(channels_.registered_scan,
                                                                 [this](RegisteredScan& s) { onRegisteredScan(s); });
  lcm_.subscribeStruct<livo::map_stats_t, MapStats>(channels_.map_stats, [this](MapStats& m) { onMapStats(m); });
  lcm_.subscribeStruct<livo::map_correction_t, MapCorrection>(channels_.map_correction,
                                                               [this](MapCorrection& c) { onMapCorrection(c); });
  if (outputs_.previousPoses() > 0 && log_)
    *log_ << "livo-exporter: continuing " << out_dir << "/trajectory.tum (" << outputs_.previousPoses()
          << " poses, the last at t " << std::fixed << std::setprecision(6) << outputs_.lastPoseTime()
          << " s): frames at or before it are left out (another run? then use a new --out)\n";
}

bool ExporterNode::acceptFrameTime(Utime t, const char* what) {
  if (!wrote_any_ || t > last_written_) return true;
  const double n = counters_[std::string(what) + "_late"] += 1;
  if (log_ && shouldWarn(std::uint64_t(n)))
    *log_ << "livo-exporter: dropped " << what << " at t=" << std::fixed << std::setprecision(6) << toSeconds(t)
          << " s: at or before the last frame written (" << toSeconds(last_written_) << " s; " << n << " so far)\n";
  return false;
}

void ExporterNode::onOdometry(const OdometryOutput& o) {
  if (!acceptFrameTime(o.utime, "odometry")) return;
  pending_[o.utime].odom = o;
  origins_[o.utime] = o.state.p_world_imu;
  while (origins_.size() > kMaxOrigins) origins_.erase(origins_.begin());
  insertHeldScans(false);
  flushFrames(false);
}

void ExporterNode::onStats(const EstimatorStats& s) {
  if (!acceptFrameTime(s.utime, "stats")) return;
  pending_[s.utime].stats = s;
  counters_["estimator_map_timeouts"] += s.map_timeout;
  counters_["estimator_dropped_points"] += s.dropped_points;
  counters_["estimator_frames_shed"] += s.frames_shed;
  counters_["estimator_images_shed"] += s.image_shed;
  counters_["estimator_max_lag_ms"] = std::max(counters_["estimator_max_lag_ms"], double(s.lag_ms));
  flushFrames(false);
}

void ExporterNode::flushFrames(bool all) {
  // The newest complete frame: it and every frame before it are written (a message of an older frame
  // that is still missing is not waited for: the estimator sends a frame's messages together).
  auto last_complete = pending_.end();
  for (auto it = pending_.begin(); it != pending_.end(); ++it)
    if (it->second.odom && it->second.stats) last_complete = it;
  auto end = all ? pending_.end() : (last_complete == pending_.end() ? pending_.begin() : std::next(last_complete));
  for (auto it = pending_.begin(); it != end;) {
    writeFrame(it->first, it->second);
    it = pending_.erase(it);
  }
  while (pending_.size() > kMaxPending) {  // the other message of a frame was lost: do not wait forever
    writeFrame(pending_.begin()->first, pending_.begin()->second);
    pending_.erase(pending_.begin());
  }
}

void ExporterNode::writeFrame(Utime t, const Pending& p) {
  FrameRecord rec;
  rec.utime = t;
  if (p.odom) {
    rec.has_pose = (p.odom->status & odometry_status::kInitializing) == 0;
    rec.T_world_imu = p.odom->state.pose();
    rec.degenerate = (p.odom->status & odometry_status::kDegenerate) != 0;
    rec.visual_used = (p.odom->status & odometry_status::kVisualUpdate) != 0;
  } else {
    counters_["frames_without_odometry"] += 1;
  }
  if (p.stats) {
    applyStats(rec, *p.stats);  // frame_row.hpp
  } else {
    counters_["frames_without_stats"] += 1;
  }
  outputs_.addFrame(rec);  // flushed per line
  if (rec.has_pose) odometry_poses_.emplace_back(t, rec.T_world_imu);
  health_.addFrame(rec);
  wrote_any_ = true;
  last_written_ = t;
}

std::optional<Eigen::Vector3d> ExporterNode::originAt(Utime t, bool nearest) const {
  if (origins_.empty()) return std::nullopt;
  auto it = origins_.lower_bound(t);
  if (it != origins_.end() && it->first == t) return it->second;
  if (!nearest) return std::nullopt;
  if (it == origins_.end()) return std::prev(it)->second;
  if (it == origins_.begin()) return it->second;
  auto before = std::prev(it);
  return (t - before->first <= it->first - t) ? before->second : it->second;
}

void ExporterNode::onRegisteredScan(const RegisteredScan& s) {
  counters_["registered_scans"] += 1;
  counters_["registered_points"] += double(s.points.size());
  cloud_.add(s.points, s.intensity, s.rgb);
  if (!cfg_.octomap_enabled) return;
  if (auto origin = originAt(s.utime, false)) {
    occupancy_.insertScan(*origin, s.points);
    return;
  }
  held_scans_.push_back(HeldScan{s.utime, s.points});
  insertHeldScans(false);
}

void ExporterNode::insertHeldScans(bool all) {
  constexpr std::size_t kMaxHeld = 8;
  for (auto it = held_scans_.begin(); it != held_scans_.end();) {
    if (auto origin = originAt(it->utime, false)) {
      occupancy_.insertScan(*origin, it->points);
      it = held_scans_.erase(it);
    } else {
      ++it;
    }
  }
  while (!held_scans_.empty() && (all || held_scans_.size() > kMaxHeld)) {
    const HeldScan& h = held_scans_.front();
    if (auto origin = originAt(h.utime, true)) {
      occupancy_.insertScan(*origin, h.points);
      counters_["scans_nearest_origin"] += 1;
    } else {
      counters_["scans_without_origin"] += 1;
    }
    held_scans_.pop_front();
  }
}

void ExporterNode::onMapStats(const MapStats& m) {
  if (!map_stats_ || m.utime >= map_stats_->utime) map_stats_ = m;
  counters_["map_stats_messages"] += 1;
}

void ExporterNode::onMapCorrection(const MapCorrection& c) {
  map_corrections_ = true;
  counters_["map_corrections"] += 1;
  const std::string why = map_frame_.apply(c);
  if (why.empty()) return;
  const double n = counters_["map_corrections_refused"] += 1;
  if (log_ && shouldWarn(std::uint64_t(n))) *log_ << "livo-exporter: map correction refused: " << why << "\n";
}

void ExporterNode::finish() {
  if (finished_) return;
  finished_ = true;
  flushFrames(true);
  insertHeldScans(true);

  if (map_corrections_) {
    TumWriter tum(outputs_.dir() + "/trajectory_map.tum");
    std::size_t written = 0;
    for (const auto& [t, T_odom] : odometry_poses_)
      if (const auto T_map = map_frame_.toMap(t, T_odom)) {
        tum.write(toSeconds(t), *T_map);
        ++written;
      }
    counters_["map_frame_poses"] = double(written);
    counters_["map_frame_keyframes"] = double(map_frame_.known());
    counters_["map_frame_final"] = map_frame_.sawFinal() ? 1.0 : 0.0;
    if (log_ && !map_frame_.sawFinal())
      *log_ << "livo-exporter: trajectory_map.tum from livo-loop's corrections so far (its final one, sent at its "
               "exit, did not arrive: stop livo-loop before the exporter)\n";
  }

  MapSummary ms;
  if (map_stats_) {
    ms.local_voxels = std::uint64_t(map_stats_->local_voxels);
    ms.visual_points_local = std::uint64_t(map_stats_->visual_points_local);
    ms.visual_points_longterm = std::uint64_t(map_stats_->visual_points_longterm);
    ms.bytes = std::uint64_t(map_stats_->bytes);
    counters_["map_local_planes"] = double(map_stats_->local_planes);
    counters_["map_bytes_cap"] = double(map_stats_->bytes_cap);
    counters_["map_evicted_visual_points"] = double(map_stats_->evicted_visual_points);
    counters_["map_evicted_voxels"] = double(map_stats_->evicted_voxels);
    counters_["map_slides"] = double(map_stats_->slides);
    counters_["map_queries_answered"] = double(map_stats_->queries_answered);
    counters_["map_last_slide_ms"] = double(map_stats_->last_slide_ms);
  }
  for (const auto& [channel, c] : lcm_.counters()) {
    counters_["received_" + channel] = double(c.received);
    counters_["rejected_" + channel] = double(c.rejected);
  }
  counters_["previous_poses"] = double(outputs_.previousPoses());
  counters_["frames_not_after_existing_files"] = double(outputs_.skippedFrames());
  counters_["map_pcd_points"] = double(cloud_.size());
  counters_["map_pcd_points_colored"] = double(cloud_.voxelsColored());
  counters_["map_points_dropped"] = double(cloud_.pointsDropped());

  const std::string& dir = outputs_.dir();
  std::map<std::string, std::string> notes{{"source", "livo-exporter"},
                                           {"peak_rss_mb_of", "livo-exporter (this process only)"}};
  if (!map_stats_) notes["map_stats"] = "no map_stats_t received: map section is zero";
  cloud_.writePcd(dir + "/map.pcd");
  if (cfg_.octomap_enabled) {
    occupancy_.writeBt(dir + "/map.bt");  // after the worker's queue is empty
    counters_["octomap_leaves"] = double(occupancy_.leafCount());
    counters_["octomap_scans"] = double(occupancy_.scansInserted());
    counters_["octomap_scans_dropped"] = double(occupancy_.scansDropped());
    counters_["octomap_scans_capped"] = double(occupancy_.scansCapped());
    counters_["octomap_mb"] = occupancy_.memoryBytes() / (1024.0 * 1024.0);
    if (const std::string note = occupancy_.capNote(); !note.empty()) notes["map_bt"] = note;
  }
  outputs_.writeStats(ms, bytesToMb(peakRssBytes()), counters_, notes, &health_);
}

std::string ExporterNode::progressLine() const {
  std::ostringstream os;
  os << "frames " << outputs_.frames() << ", poses " << outputs_.posesWritten() << ", map points " << cloud_.size()
     << ", octomap scans " << occupancy_.scansInserted() << ", rejected " << lcm_.totalRejected();
  return os.str();
}

std::string ExporterNode::summary() const {
  std::ostringstream os;
  os << outputs_.summary(bytesToMb(peakRssBytes()));
  os << "map.pcd " << cloud_.size() << " points (" << cloud_.voxelsColored() << " coloured, " << cloud_.pointsDropped()
     << " dropped), map.bt " << occupancy_.scansInserted() << " scans\n";
  if (const std::string note = occupancy_.capNote(); !note.empty()) os << note << "\n";
  os << "messages:\n" << lcm_.countersSummary();
  for (const auto& [k, v] : counters_)
    if (k.find("late") != std::string::npos || k.find("without") != std::string::npos)
      os << "  " << k << ": " << v << "\n";
  if (outputs_.previousPoses() > 0)
    os << "continued files holding " << outputs_.previousPoses() << " poses; frames left out (not after their end) "
       << outputs_.skippedFrames() << "\n";
  os << "outputs in " << outputs_.dir() << "\n";
  os << "CPU time " << processCpuSeconds() << " s\n";  // peak RSS: in the outputs' summary above
  return os.str();
}

}  // namespace livo
