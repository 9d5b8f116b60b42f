#include "livo/process/estimator_node.hpp"

#include "livo/common/timing.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/io/frame_row.hpp"
#include "livo/io/map_messages.hpp"
#include "livo/process/scan_colour.hpp"

#include <livo/resume_request_t.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <sstream>

namespace livo {

void EstimatorNodeConfig::load(const ConfigNode& s) {
  s.get("map_timeout_ms", map_timeout_ms)
      .get("fast_timeout_ms", fast_timeout_ms)
      .get("fast_timeouts_after", fast_timeouts_after)
      .get("max_queued_frames", max_queued_frames)
      .get("resume_wait_ms", resume_wait_ms)
      .get("resume_max_gap_s", resume_max_gap_s)
      .get("shed_images_queued", shed_images_queued)
      .get("shed_frames_queued", shed_frames_queued);
  s.check(map_timeout_ms > 0 && map_timeout_ms <= 60000, "map_timeout_ms", "must be in (0, 60000]");
  s.check(fast_timeout_ms > 0 && fast_timeout_ms <= map_timeout_ms, "fast_timeout_ms",
          "must be in (0, map_timeout_ms]");
  s.check(fast_timeouts_after >= 1, "fast_timeouts_after", "must be >= 1");
  s.check(max_queued_frames >= 1 && max_queued_frames <= 100000, "max_queued_frames", "must be in [1, 100000]");
  s.check(resume_wait_ms >= 0 && resume_wait_ms <= 60000, "resume_wait_ms", "must be in [0, 60000]");
  s.check(resume_max_gap_s > 0 && resume_max_gap_s <= 3600, "resume_max_gap_s", "must be in (0, 3600]");
  s.check(shed_images_queued >= 0, "shed_images_queued", "must be >= 0");
  s.check(shed_frames_queued >= 1 && shed_frames_queued <= max_queued_frames, "shed_frames_queued",
          "must be in [1, max_queued_frames]");
}

EstimatorNode::EstimatorNode(LcmNode& lcm, PipelineConfig pipeline, EstimatorNodeConfig cfg,
                             const ChannelConfig& channels, std::ostream* log)
    : lcm_(lcm), cfg_(cfg), channels_(channels), log_(log), pipeline_(pipeline), map_(pipeline, *this) {
  lcm_.subscribe<livo::frame_t>(channels_.frame, [this](const livo::frame_t& m) {
    Queued item;
    Validation v = fromMsg(m, item.frame, lcm_.limits(), &item.nonfinite);
    if (!v) return v;
    item.arrived = std::chrono::steady_clock::now();
    queue_.push_back(std::move(item));
    while (int(queue_.size()) > cfg_.max_queued_frames) {
      dropOldest();
      if (shouldWarn(++counters_.frames_dropped) && log_)
        *log_ << "livo-estimator: warning: frame queue full (" << cfg_.max_queued_frames
              << "), dropped the oldest frame, its IMU merged into the next (" << counters_.frames_dropped
              << " so far)\n";
    }
    return Validation::ok();
  });
  lcm_.subscribe<livo::submap_t>(channels_.submap, [this](const livo::submap_t& m) {
    if (m.request_id != waiting_for_ || answered_) {
      ++counters_.late_submaps;  // an answer nobody waits for any more (or a duplicate)
      return Validation::ok();
    }
    Submap s;
    Validation v = fromMsg(m, s, lcm_.limits());
    if (!v) {
      ++counters_.invalid_submaps;
      return v;
    }
    counters_.submap_bytes += std::uint64_t(m.getEncodedSize());
    answer_ = std::move(s);
    answered_ = true;
    return Validation::ok();
  });
  if (cfg_.resume_wait_ms > 0) {
    lcm_.subscribe<livo::resume_t>(channels_.resume, [this](const livo::resume_t& m) {
      if (m.request_id != resume_request_id_ || resume_answered_) return Validation::ok();  // another estimator's
      ResumeAnswer a;
      Validation v = fromMsg(m, a, lcm_.limits());
      if (!v) return v;
      resume_ = std::move(a);
      resume_answered_ = true;
      return Validation::ok();
    });
    sendResumeRequest();
  } else {
    started_ = true;
    start_report_ = "new origin: resume_wait_ms is 0";
  }
}

bool EstimatorNode::startFrom(const Frame& first) {
  started_ = true;
  // The request went out at construction. Unanswered and its wait over before the first frame came
  // (the map server was started after this estimator): ask again.
  if (!resume_answered_ && since_resume_request_.elapsedMs() >= cfg_.resume_wait_ms) sendResumeRequest();
  awaitResumeAnswer();
  refuseOtherConfig();
  std::ostringstream why;
  why << std::fixed << std::setprecision(3);
  if (!resume_answered_) {
    why << "new origin: no answer from the map server within resume_wait_ms (" << cfg_.resume_wait_ms << " ms)";
  } else if (!resume_.have_state) {
    why << "new origin: the map server holds no filter state (a new run)";
  } else {
    const Utime t0 = resume_.snapshot.filter.state.utime;
    const double gap = toSeconds(first.utime - t0);
    if (gap <= 0) {
      why << "new origin: the map server's last state (t " << toSeconds(t0) << " s) is not older than the first frame (t "
          << toSeconds(first.utime) << " s): another run";
    } else if (gap > cfg_.resume_max_gap_s) {
      why << "new origin: the map server's last state is " << gap << " s older than the first frame (resume_max_gap_s "
          << cfg_.resume_max_gap_s << ")";
    } else {
      std::ostringstream src;
      src << std::fixed << std::setprecision(3) << "the map server's last filter state (" << gap << " s before the first frame, "
          << resume_.snapshot.frames << " frames of the previous estimator";
      if (resume_.imu_dropped > 0) src << ", " << resume_.imu_dropped << " IMU samples lost";
      src << ")";
      pipeline_.resume(resume_.snapshot.filter, std::move(resume_.imu), src.str());
      start_report_ = "resumed";
      resume_ = ResumeAnswer{};
      return true;
    }
  }
  start_report_ = why.str();
  resume_ = ResumeAnswer{};
  if (log_) *log_ << "livo-estimator: " << start_report_ << "\n";
  return false;
}

bool EstimatorNode::request(const MapQuery& q, Submap& out) {
  const livo::map_query_t m = toMsg(q);
  counters_.query_bytes += std::uint64_t(m.getEncodedSize());
  waiting_for_ = q.request_id;
  answered_ = false;
  ++counters_.queries;
  Stopwatch rt;
  lcm_.publish(channels_.map_query, m);
  const double limit = timeouts_in_row_ >= cfg_.fast_timeouts_after ? cfg_.fast_timeout_ms : cfg_.map_timeout_ms;
  while (!answered_) {
    const double left = limit - rt.elapsedMs();
    if (left <= 0) break;
    lcm_.handleOnce(std::max(1, int(left)));
  }
  if (!answered_) lcm_.drain();  // an answer that arrived while the deadline passed still counts
  waiting_for_ = -1;
  if (!answered_) {
    ++counters_.timeouts;
    ++timeouts_in_row_;
    if (shouldWarn(counters_.timeouts) && log_)
      *log_ << "livo-estimator: warning: no submap for request " << q.request_id << " within " << limit
            << " ms (" << counters_.timeouts << " timeouts so far); continuing with the planes it has\n";
    return false;
  }
  const double ms = rt.elapsedMs();
  counters_.max_round_trip_ms = std::max(counters_.max_round_trip_ms, ms);
  counters_.sum_round_trip_ms += ms;
  ++counters_.answered;
  if (timeouts_in_row_ > 0 && log_) *log_ << "livo-estimator: the map server answers again\n";
  timeouts_in_row_ = 0;
  out = std::move(answer_);
  return true;
}

void EstimatorNode::send(const MapUpdate& u) {
  const livo::map_update_t m = toMsg(u);
  counters_.update_bytes += std::uint64_t(m.getEncodedSize());
  lcm_.publish(channels_.map_update, m);
}

std::size_t EstimatorNode::poll() {
  if (in_poll_) return 0;  // request() handles messages: never re-enter
  refuseOtherConfig();     // as soon as the map server's answer says so, not at the first frame
  in_poll_ = true;
  std::size_t n = 0;
  while (!queue_.empty()) {
    // Overload: whole frames first beyond shed_frames_queued (IMU kept), then the image of a frame
    // while the LiDAR holds on its own.
    while (int(queue_.size()) - 1 > cfg_.shed_frames_queued) {
      dropOldest();
      if (shouldWarn(++counters_.frames_shed) && log_)
        *log_ << "livo-estimator: warning: " << queue_.size() << " frames waiting, shed the oldest (IMU kept; "
              << counters_.frames_shed << " so far)\n";
    }
    const bool shed_image = int(queue_.size()) - 1 > cfg_.shed_images_queued && !last_degenerate_ &&
                            queue_.front().frame.has_image;
    Queued item = std::move(queue_.front());
    queue_.pop_front();
    processFrame(item, shed_image);
    ++n;
  }
  in_poll_ = false;
  return n;
}

std::int64_t EstimatorNode::newRequestId() {
  // The pid and the clock: another estimator's request (and its answer) has another id.
  return (std::int64_t(::getpid()) << 32) ^ std::chrono::steady_clock::now().time_since_epoch().count();
}

void EstimatorNode::sendResumeRequest() {
  resume_request_id_ = newRequestId();
  resume_answered_ = false;
  since_resume_request_.restart();
  publishResumeRequest();
}

void EstimatorNode::publishResumeRequest() {
  livo::resume_request_t q{};
  q.request_id = resume_request_id_;
  q.config = cfg_.config_lines;
  since_resume_publish_.restart();
  lcm_.publish(channels_.resume_request, q);
}

bool EstimatorNode::awaitResumeAnswer() {
  constexpr double kRepeatMs = 100.0;
  while (!resume_answered_) {
    const double left = cfg_.resume_wait_ms - since_resume_request_.elapsedMs();
    if (left <= 0) break;
    if (since_resume_publish_.elapsedMs() >= kRepeatMs) publishResumeRequest();  // same id: one answer counts
    lcm_.handleOnce(std::max(1, int(std::min(left, kRepeatMs - since_resume_publish_.elapsedMs()))));
  }
  return resume_answered_;
}

bool EstimatorNode::askMapServer() {
  sendResumeRequest();
  return awaitResumeAnswer();
}

void EstimatorNode::refuseOtherConfig() const {
  if (resume_answered_ && !resume_.config_mismatch.empty())
    throw std::runtime_error("the running map server's config differs from this one: " + resume_.config_mismatch +
                             " (another rig? start every process of the suite with the same --config)");
}

bool EstimatorNode::bridgeImuGap(Frame& frame) {
  const Utime t_state = pipeline_.filter().x().utime;
  const double gap = toSeconds(frame.imu.front().utime - t_state);
  ++counters_.imu_gaps;
  std::ostringstream os;
  os << std::fixed << std::setprecision(3) << "livo-estimator: the frame at t " << toSeconds(frame.utime)
     << " s has no IMU sample for the first " << gap << " s after the last state (frames lost upstream): ";
  bool bridged = false;
  const bool answered = cfg_.resume_wait_ms > 0 && askMapServer();
  refuseOtherConfig();
  if (cfg_.resume_wait_ms <= 0) {
    os << "resume_wait_ms is 0, not asked";
  } else if (!answered) {
    os << "no answer from the map server; the filter holds the first sample across the gap";
  } else if (!resume_.have_state || resume_.snapshot.filter.state.utime != t_state) {
    os << "the map server holds samples after another state; the filter holds the first sample across the gap";
  } else {
    std::vector<ImuSample> imu;
    for (const ImuSample& s : resume_.imu)
      if (s.utime > t_state && s.utime < frame.imu.front().utime) imu.push_back(s);
    counters_.imu_bridged_samples += imu.size();
    os << imu.size() << " samples from the map server fill it";
    imu.insert(imu.end(), frame.imu.begin(), frame.imu.end());
    frame.imu = std::move(imu);
    bridged = true;
  }
  resume_ = ResumeAnswer{};
  if (log_ && shouldWarn(counters_.imu_gaps)) *log_ << os.str() << "\n";
  return bridged;
}

void EstimatorNode::dropOldest() {
  if (queue_.size() < 2) return;
  Queued& old = queue_[0];
  Queued& next = queue_[1];
  std::vector<ImuSample> imu;
  const Utime first_next = next.frame.imu.empty() ? next.frame.utime : next.frame.imu.front().utime;
  for (const ImuSample& s : old.frame.imu)
    if (s.utime < first_next) imu.push_back(s);
  imu.insert(imu.end(), next.frame.imu.begin(), next.frame.imu.end());
  next.frame.imu = std::move(imu);
  next.nonfinite += old.nonfinite;
  next.shed_before += old.shed_before + 1;
  queue_.pop_front();
}


void EstimatorNode::processFrame(Queued& q, bool shed_image) {
  const std::size_t nonfinite = q.nonfinite;
  if (shed_image) {
    q.frame.has_image = false;
    q.frame.image = Image();
    ++counters_.images_shed;
  }
  // The resume answer's samples bridge the first frame's gap (startFrom).
  const bool resumed_now = !started_ && startFrom(q.frame);
  // IMU lost upstream (a restarted preprocessor, dropped frames): the map server holds the samples
  // after this estimator's last state.
  const double period_s = 1.0 / pipeline_.config().lio.imu.rate_hz;
  if (!resumed_now && pipeline_.odometry().initialized() && !q.frame.imu.empty() &&
      toSeconds(q.frame.imu.front().utime - pipeline_.filter().x().utime) > 3.0 * period_s)
    bridgeImuGap(q.frame);
  const Frame& frame = q.frame;
  counters_.nonfinite_points += nonfinite;
  const FrameResult f = pipeline_.process(frame, map_);
  ++counters_.frames;
  counters_.last_utime = frame.utime;

  last_degenerate_ = f.degenerate;
  EstimatorStats st = frameStats(f, frame.utime, std::int64_t(counters_.frames - 1), nonfinite);
  st.lag_ms = float(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - q.arrived).count());
  st.frames_shed = q.shed_before;
  st.image_shed = shed_image;
  lag_ms_.add(st.lag_ms);
  max_lag_ms_ = std::max(max_lag_ms_, double(st.lag_ms));
  lcm_.publish(channels_.estimator_stats, toMsg(st));
  if (!f.lio.initialized) {  // no pose yet: say why, once per second of sensor time
    if (log_ && (last_wait_said_ < 0 || toSeconds(frame.utime - last_wait_said_) >= 1.0)) {
      last_wait_said_ = frame.utime;
      *log_ << "livo-estimator: no pose yet: " << pipeline_.odometry().waitMessage() << "\n";
    }
    return;
  }
  if (!announced_init_ && log_) {
    *log_ << "livo-estimator: " << pipeline_.odometry().initMessage() << "\n";
    announced_init_ = true;
  }

  OdometryOutput o;
  o.utime = frame.utime;
  o.state = f.lio.state;
  o.pose_cov = f.lio.P.topLeftCorner<6, 6>();
  o.pose_cov = 0.5 * (o.pose_cov + o.pose_cov.transpose()).eval();
  o.status = 0;
  if (f.degenerate) o.status |= odometry_status::kDegenerate;
  if (f.visual_used) o.status |= odometry_status::kVisualUpdate;
  if (f.link.map_timeout) o.status |= odometry_status::kMapTimeout;
  if (f.lidarFailed()) o.status |= odometry_status::kLidarFailed;
  if (f.lio.lio_ok) o.status |= odometry_status::kLidarUpdate;
  if (f.health.state == HealthState::Degraded) o.status |= odometry_status::kDegraded;
  if (f.health.state == HealthState::Lost) o.status |= odometry_status::kLost;
  lcm_.publish(channels_.odometry, toMsg(o));
  ++counters_.odometry_published;
  // The whole filter state, for an estimator that restarts (the map server keeps the latest).
  FilterSnapshot snap;
  snap.filter = pipeline_.filter().snapshot();
  snap.frames = std::int64_t(counters_.frames);
  lcm_.publish(channels_.filter_state, toMsg(snap));

  if (!f.lio.points.empty()) {
    const CameraModel* cam = pipeline_.camera();
    const PipelineConfig& pc = pipeline_.config();
    const RegisteredScan scan = colourScan(frame.utime, f.lio.state.pose(), f.lio.points, cam,
                                           frame.has_image ? &frame.image : nullptr, pc.camera.T_imu_camera,
                                           pc.camera.scale);
    lcm_.publish(channels_.registered_scan, toMsg(scan));
  }
}

std::string EstimatorNode::progressLine() const {
  std::ostringstream os;
  os << std::fixed << std::setprecision(3) << "t " << toSeconds(counters_.last_utime) << " s: frames "
     << counters_.frames << ", queued " << queue_.size() << ", queries " << counters_.queries << " (timeouts "
     << counters_.timeouts << ", late answers " << counters_.late_submaps << "), rejected " << lcm_.totalRejected();
  return os.str();
}

std::string EstimatorNode::summary() const {
  std::ostringstream os;
  const double answered = std::max<double>(1.0, double(counters_.answered));
  os << std::fixed << std::setprecision(2);
  os << "frames " << counters_.frames << " (dropped from the queue " << counters_.frames_dropped << "), odometry "
     << counters_.odometry_published << "\n";
  os << "load: lag ms (arrival -> outputs) median " << lag_ms_.quantile(0.5) << ", p95 " << lag_ms_.quantile(0.95)
     << ", max " << max_lag_ms_ << "; frames shed "
     << counters_.frames_shed << " (more than " << cfg_.shed_frames_queued << " waiting), images shed "
     << counters_.images_shed << " (more than " << cfg_.shed_images_queued << " waiting, LiDAR not degenerate)\n";
  os << "start: " << (start_report_.empty() ? "no frame" : start_report_) << "; IMU gaps " << counters_.imu_gaps
     << " (samples from the map server " << counters_.imu_bridged_samples << ")\n";
  os << "map queries " << counters_.queries << ": answered " << counters_.answered << ", timeouts "
     << counters_.timeouts << ", late answers " << counters_.late_submaps << ", invalid answers "
     << counters_.invalid_submaps << "\n";
  os << "round trip ms: mean " << counters_.sum_round_trip_ms / answered << ", max " << counters_.max_round_trip_ms
     << "\n";
  os << "bytes per message: query " << double(counters_.query_bytes) / std::max<double>(1.0, double(counters_.queries))
     << ", submap " << double(counters_.submap_bytes) / answered << ", update "
     << double(counters_.update_bytes) / std::max<double>(1.0, double(counters_.frames)) << "\n";
  os << "voxel size mismatches " << map_.voxelSizeMismatches() << ", images of the wrong size "
     << pipeline_.imagesWrongSize() << ", non-finite points " << counters_.nonfinite_points << "\n";
  const ImageCheckCounters& ic = pipeline_.imageCounters();
  os << "camera failures: black " << ic.black << ", saturated " << ic.saturated << ", frozen " << ic.frozen
     << ", missing " << ic.missing << "\n";
  if (pipeline_.config().vio.estimate_time_offset)
    os << "camera time offset resets " << pipeline_.timeOffsetResets() << "\n";
  os << resourceSummary() << "\n";
  os << "messages:\n" << lcm_.countersSummary();
  return os.str();
}

}  // namespace livo
