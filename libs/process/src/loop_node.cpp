#include "livo/process/loop_node.hpp"

#include "livo/io/loop_messages.hpp"

#include <iomanip>
#include <sstream>

namespace livo {

LoopNode::LoopNode(LcmNode& lcm, const ChannelConfig& channels, const LoopConfig& cfg, std::ostream* log,
                   SiteMap* prior_map)
    : lcm_(lcm), channels_(channels), log_(log) {
  if (prior_map) reloc_ = std::make_unique<Relocaliser>(cfg, *prior_map);
  else closer_.emplace(cfg);
  lcm_.subscribeStruct<livo::odometry_t, OdometryOutput>(channels_.odometry,
                                                          [this](OdometryOutput& o) { onOdometry(o); });
  lcm_.subscribeStruct<livo::registered_scan_t, RegisteredScan>(channels_.registered_scan,
                                                                 [this](RegisteredScan& s) { onRegisteredScan(s); });
}

bool LoopNode::accept(Utime t, const char* what) {
  if (!took_any_ || t > last_taken_) return true;
  const double n = counters_[std::string(what) + "_late"] += 1;
  if (log_ && shouldWarn(std::uint64_t(n)))
    *log_ << "livo-loop: dropped " << what << " at t=" << std::fixed << std::setprecision(6) << toSeconds(t)
          << " s: at or before the last frame taken (" << toSeconds(last_taken_) << " s; " << n << " so far)\n";
  return false;
}

void LoopNode::onOdometry(const OdometryOutput& o) {
  if (o.status & odometry_status::kInitializing) {
    counters_["odometry_initializing"] += 1;
    return;
  }
  if (!accept(o.utime, "odometry")) return;
  if (!pending_.empty() && o.utime <= pending_.back().utime) {
    counters_["odometry_out_of_order"] += 1;
    return;
  }
  pending_.push_back(o);
  pump(false);
}

void LoopNode::onRegisteredScan(const RegisteredScan& s) {
  if (!accept(s.utime, "scan")) return;
  scans_[s.utime] = s.points;
  while (scans_.size() > kMaxScans) {
    scans_.erase(scans_.begin());
    counters_["scans_without_odometry"] += 1;
  }
  pump(false);
}

void LoopNode::pump(bool all) {
  while (!pending_.empty()) {
    const Utime t = pending_.front().utime;
    const auto it = scans_.find(t);
    const bool later_scan = !scans_.empty() && scans_.rbegin()->first > t;
    if (it == scans_.end() && !all && !later_scan && pending_.size() <= kWaitFrames) return;
    take(pending_.front(), it == scans_.end() ? nullptr : &it->second);
    while (!scans_.empty() && scans_.begin()->first <= t) {
      if (scans_.begin()->first < t) counters_["scans_without_odometry"] += 1;
      scans_.erase(scans_.begin());
    }
    pending_.pop_front();
  }
}

void LoopNode::take(const OdometryOutput& o, const std::vector<Eigen::Vector3f>* scan) {
  took_any_ = true;
  last_taken_ = o.utime;
  counters_["frames"] += 1;
  if (!scan) counters_["frames_without_scan"] += 1;
  const auto points = [&] {
    std::vector<Vec3> pts;
    if (scan) {
      pts.reserve(scan->size());
      for (const Eigen::Vector3f& p : *scan) pts.push_back(p.cast<double>());
    }
    return pts;
  };
  if (reloc_) {
    const RelocaliseStep st = reloc_->add(o.utime, o.state.pose(), points);
    if (log_ && (st.localised_now || st.back_in_map || st.left_map))
      *log_ << "livo-loop: " << (st.left_map ? "outside the site map" : st.back_in_map ? "back in the site map" : "localised in the site map")
            << " at t=" << std::fixed << std::setprecision(3) << toSeconds(o.utime) << " s\n";
    if (st.matched) publish(false, false);
    return;
  }
  const LoopStep st = closer_->add(o.utime, o.state.pose(), points);
  if (!st.keyframe) return;
  if (!scan) counters_["keyframes_without_scan"] += 1;
  if (st.loop && log_)
    *log_ << "livo-loop: loop at t=" << std::fixed << std::setprecision(3) << toSeconds(o.utime) << " s: keyframe "
          << st.node << " with " << st.loop_with << (st.solved ? ", graph solved" : ", agrees with the map frame")
          << "\n";
  publish(false, false);
}

void LoopNode::publish(bool all, bool final) {
  if (reloc_) {
    MapCorrection c = reloc_->anchors(all);
    c.final = final;
    lcm_.publish(channels_.map_correction, toMsg(c));
  } else {
    lcm_.publish(channels_.map_correction, toMsg(closer_->correctionMessage(all, final)));
  }
  counters_["corrections_published"] += 1;
}

void LoopNode::finish() {
  if (finished_) return;
  finished_ = true;
  pump(true);
  counters_["scans_without_odometry"] += double(scans_.size());
  scans_.clear();
  if (closer_) closer_->finish();
  publish(true, true);
}

std::string LoopNode::progressLine() const {
  std::ostringstream os;
  const auto frames = counters_.find("frames");
  os << "frames " << (frames == counters_.end() ? 0.0 : frames->second) << " taken; "
     << (closer_ ? closer_->summary() : reloc_->summary()) << ", rejected "
     << lcm_.totalRejected();
  return os.str();
}

std::string LoopNode::summary() const {
  std::ostringstream os;
  if (closer_) os << "loop closure: " << closer_->summary() << "\n";
  else os << "site map " << reloc_->summary() << "\n";
  std::map<std::string, double> c = counters_;
  if (closer_) closer_->addCounters(c);
  else reloc_->addCounters(c);
  for (const auto& [k, v] : c) os << "  " << k << ": " << v << "\n";
  os << "messages:\n" << lcm_.countersSummary();
  return os.str();
}

}  // namespace livo
