// LCM -> ROS (estimator_outputs.hpp).
#include "estimator_outputs.hpp"

#include "ros_messages.hpp"

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>

namespace livo_bridge {

namespace {

using Clock = std::chrono::steady_clock;

/// decode() + fromMsg() of a raw LCM message into T.
template <class Msg, class T>
livo::Validation decodeInto(const void* data, std::size_t size, T& out, const livo::MessageLimits& lim) {
  Msg m;
  livo::Validation v = livo::decode(data, size, m, lim);
  return v ? livo::convertMessage(m, out, lim) : v;
}

}  // namespace

EstimatorOutputs::EstimatorOutputs(const BridgeOptions& opt, livo::LcmNode& lcm, BridgeLog& log)
    : opt_(opt),
      channels_{opt.channels.odometry, opt.channels.registered_scan, opt.channels.estimator_stats,
                opt.channels.map_stats},
      log_(log),
      map_(opt.map_voxel_m, opt.map_max_points) {
  const livo::MessageLimits& lim = lcm.limits();
  lcm.subscribeRaw(channels_[kOdometry], [this, &lim](const void* data, std::size_t size) {
    const auto t = Clock::now();
    livo::OdometryOutput o;
    livo::Validation v = decodeInto<livo::odometry_t>(data, size, o, lim);
    if (v) push(kOdometry, std::move(o), t);
    return v;
  });
  lcm.subscribeRaw(channels_[kScan], [this, &lim](const void* data, std::size_t size) {
    const auto t = Clock::now();
    livo::registered_scan_t m;  // kept as decoded: its arrays become the PointCloud2 directly
    livo::Validation v = livo::decode(data, size, m, lim);
    if (v) v = livo::validate(m, lim);
    if (v) push(kScan, std::move(m), t);
    return v;
  });
  lcm.subscribeRaw(channels_[kEstimatorStats], [this, &lim](const void* data, std::size_t size) {
    const auto t = Clock::now();
    livo::EstimatorStats s;
    livo::Validation v = decodeInto<livo::estimator_stats_t>(data, size, s, lim);
    if (v) push(kEstimatorStats, std::move(s), t);
    return v;
  });
  lcm.subscribeRaw(channels_[kMapStats], [this, &lim](const void* data, std::size_t size) {
    const auto t = Clock::now();
    livo::MapStats s;
    livo::Validation v = decodeInto<livo::map_stats_t>(data, size, s, lim);
    if (v) push(kMapStats, std::move(s), t);
    return v;
  });
}

EstimatorOutputs::~EstimatorOutputs() { stop(); }

void EstimatorOutputs::advertise(ros::NodeHandle& nh) {
  // The old publications go first: roscpp registers a topic with the master only when this node does not
  // advertise it yet. Under pub_mu_, which the publisher thread holds while it publishes.
  std::lock_guard<std::mutex> lock(pub_mu_);
  for (ros::Publisher* old : {&pub_.odometry, &pub_.tf, &pub_.scan, &pub_.map, &pub_.diagnostics}) old->shutdown();
  Publishers& p = pub_;
  const std::string& pre = opt_.topic_prefix;
  const auto q = static_cast<std::uint32_t>(opt_.queue);
  p.odometry = nh.advertise<nav_msgs::Odometry>(pre + "/odometry", q);
  p.tf = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
  p.scan = nh.advertise<sensor_msgs::PointCloud2>(pre + "/registered_scan", q);
  p.map = nh.advertise<sensor_msgs::PointCloud2>(pre + "/map", 1, /*latch=*/true);
  p.diagnostics = nh.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10);
}

std::vector<std::string> EstimatorOutputs::topics() const {
  const std::string& pre = opt_.topic_prefix;
  return {pre + "/odometry", "/tf", pre + "/registered_scan", pre + "/map", "/diagnostics"};
}

void EstimatorOutputs::push(Kind kind, Value&& v, Clock::time_point received) {
  std::uint64_t dropped = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    ++stats_[kind].received;
    if (queued_[kind] >= static_cast<std::size_t>(opt_.queue)) {  // the oldest of this channel goes
      auto it = std::find_if(queue_.begin(), queue_.end(), [kind](const Item& i) { return i.kind == kind; });
      queue_.erase(it);
      --queued_[kind];
      dropped = ++stats_[kind].dropped;
    }
    queue_.push_back(Item{kind, std::move(v), received});
    ++queued_[kind];
  }
  cv_.notify_one();
  if (dropped > 0) log_.every(dropped, channels_[kind] + ": queue full, oldest message dropped");
}

void EstimatorOutputs::start() {
  stop_ = false;
  next_diagnostics_ = Clock::now();
  thread_ = std::thread([this] { run(); });
}

void EstimatorOutputs::stop() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void EstimatorOutputs::run() {
  for (;;) {
    std::optional<Item> item;
    {
      std::unique_lock<std::mutex> lock(mu_);
      cv_.wait_until(lock, next_diagnostics_, [this] { return stop_ || !queue_.empty(); });
      if (!queue_.empty()) {
        item = std::move(queue_.front());
        queue_.pop_front();
        --queued_[item->kind];
      } else if (stop_) {
        return;
      }
    }
    std::lock_guard<std::mutex> lock(pub_mu_);  // advertise() waits for the message in progress
    if (item) handle(*item, pub_);
    if (Clock::now() >= next_diagnostics_) {
      publishDiagnostics(pub_);
      next_diagnostics_ = Clock::now() + std::chrono::seconds(1);
    }
  }
}

void EstimatorOutputs::handle(Item& item, const Publishers& pub) {
  std::size_t published = 0;
  std::string error;
  std::optional<Clock::time_point> done;  // when the message itself was handed to roscpp
  if (!pub.odometry) {  // not registered with a ROS master yet: nobody to publish to
    std::lock_guard<std::mutex> lock(mu_);
    ++stats_[item.kind].skipped;
    return;
  }
  try {
    switch (item.kind) {
      case kOdometry: {
        const auto& o = std::get<livo::OdometryOutput>(item.value);
        pub.odometry.publish(toRosOdometry(o, opt_.world_frame, opt_.body_frame));
        tf2_msgs::TFMessage tf;
        tf.transforms.push_back(toRosTransform(o, opt_.world_frame, opt_.body_frame));
        pub.tf.publish(tf);
        last_odometry_ = o;
        last_odometry_wall_ = Clock::now();
        published = 1;
        break;
      }
      case kScan: {
        const auto& m = std::get<livo::registered_scan_t>(item.value);
        if (pub.scan.getNumSubscribers() > 0) pub.scan.publish(toRosCloud(m, opt_.world_frame));
        done = Clock::now();  // the map's upkeep below is not this message's latency
        const bool coloured = m.num_colors > 0 && m.num_colors == m.num_points;
        map_.add(static_cast<std::size_t>(m.num_points), m.x.data(), m.y.data(), m.z.data(), m.intensity.data(),
                 coloured ? m.rgb.data() : nullptr);
        if (m.utime >= next_map_utime_) {
          publishMap(pub, m.utime);
          next_map_utime_ = m.utime + static_cast<livo::Utime>(opt_.map_period_s * 1e6);
        }
        published = 1;
        break;
      }
      case kEstimatorStats:
        last_estimator_stats_ = std::get<livo::EstimatorStats>(item.value);
        published = 1;  // into the next diagnostics
        break;
      case kMapStats:
        last_map_stats_ = std::get<livo::MapStats>(item.value);
        last_map_stats_wall_ = Clock::now();
        published = 1;
        break;
      case kKinds: break;
    }
  } catch (const std::exception& e) {  // roscpp throws for a publisher in a bad state
    error = e.what();
  }
  const double latency = std::chrono::duration<double>(done.value_or(Clock::now()) - item.received).count();
  std::uint64_t rejected = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    StreamStats& s = stats_[item.kind];
    s.published += published;
    if (published) s.latency.add(latency);
    if (!error.empty()) {
      rejected = ++s.rejected;
      s.last_error = error;
    }
  }
  if (rejected) log_.every(rejected, channels_[item.kind] + ": ROS publish failed: " + error);
}

void EstimatorOutputs::publishMap(const Publishers& pub, livo::Utime utime) {
  if (pub.map.getNumSubscribers() == 0) return;  // latched: the next one after a subscriber comes
  sensor_msgs::PointCloud2 c;
  c.header.stamp = rosTime(utime);
  c.header.frame_id = opt_.world_frame;
  fillCloud(c, map_.size(), map_.x().data(), map_.y().data(), map_.z().data(), map_.intensity().data(),
            map_.coloured() ? map_.rgb().data() : nullptr);
  pub.map.publish(c);
}

void EstimatorOutputs::setBridgeStatus(std::vector<std::pair<std::string, std::string>> values, bool warn) {
  std::lock_guard<std::mutex> lock(mu_);
  bridge_values_ = std::move(values);
  bridge_warn_ = warn;
}

void EstimatorOutputs::publishDiagnostics(const Publishers& pub) {
  if (!pub.diagnostics) return;
  const auto now = Clock::now();
  const bool odo_fresh = last_odometry_ && now - last_odometry_wall_ < std::chrono::seconds(2);
  const bool map_fresh = last_map_stats_ && now - last_map_stats_wall_ < std::chrono::seconds(3);
  diagnostic_msgs::DiagnosticArray a;
  a.header.stamp = ros::Time::now();
  a.status.push_back(estimatorStatus(odo_fresh ? &*last_odometry_ : nullptr,
                                     last_estimator_stats_ ? &*last_estimator_stats_ : nullptr));
  a.status.push_back(mapServerStatus(map_fresh ? &*last_map_stats_ : nullptr));
  diagnostic_msgs::DiagnosticStatus b;
  b.name = "livo: ros bridge";
  b.hardware_id = "livo";
  {
    std::lock_guard<std::mutex> lock(mu_);
    b.level = bridge_warn_ ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK;
    b.message = bridge_warn_ ? "messages rejected or dropped since the last report" : "ok";
    for (const auto& [k, v] : bridge_values_) {
      diagnostic_msgs::KeyValue kv;
      kv.key = k;
      kv.value = v;
      b.values.push_back(kv);
    }
  }
  a.status.push_back(b);
  pub.diagnostics.publish(a);
}

std::map<std::string, StreamStats> EstimatorOutputs::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  std::map<std::string, StreamStats> out;
  for (int k = 0; k < kKinds; ++k) out[channels_[k]] = stats_[k];
  return out;
}

}  // namespace livo_bridge
