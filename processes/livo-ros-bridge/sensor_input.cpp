// ROS -> LCM for one role (sensor_input.hpp).
#include "sensor_input.hpp"

#include "livo/io/convert.hpp"

#include <ros/subscribe_options.h>
#include <ros/subscription_callback_helper.h>

#include <boost/make_shared.hpp>

#include <chrono>

namespace livo_bridge {

namespace {

const std::string& channelOf(livo::RosRole role, const livo::ChannelConfig& c) {
  switch (role) {
    case livo::RosRole::Lidar: return c.lidar;
    case livo::RosRole::Imu: return c.imu;
    case livo::RosRole::Camera: break;
  }
  return c.camera;
}

double wallNow() { return ros::WallTime::now().toSec(); }

}  // namespace

SensorInput::SensorInput(livo::RosRole role, const BridgeOptions& opt, livo::LcmNode& lcm, BridgeLog& log)
    : role_(role),
      wanted_(livo::roleTopicOption(opt.input, role)),
      channel_(channelOf(role, opt.channels)),
      queue_size_(role == livo::RosRole::Imu ? opt.imu_queue : opt.queue),
      lcm_(lcm),
      log_(log),
      decoder_(opt.input),
      gate_(opt.input) {}

SensorInput::~SensorInput() { stop(); }

bool SensorInput::subscribe(ros::NodeHandle& nh, const std::string& topic, const std::string& datatype) {
  using Helper = ros::SubscriptionCallbackHelperT<const ros::MessageEvent<RosWireMessage const>&>;
  ros::SubscribeOptions ops;
  ops.topic = topic;
  ops.queue_size = static_cast<std::uint32_t>(queue_size_);
  ops.md5sum = "*";
  ops.datatype = "*";
  ops.helper = boost::make_shared<Helper>([this](const ros::MessageEvent<RosWireMessage const>& ev) { onMessage(ev); },
                                          [this] {
                                            auto m = boost::make_shared<RosWireMessage>();
                                            m->decoder = this;
                                            return m;
                                          });
  ops.callback_queue = &queue_;
  ops.transport_hints = ros::TransportHints().tcpNoDelay();
  ros::Subscriber s = nh.subscribe(ops);
  if (!s) return false;
  std::lock_guard<std::mutex> lock(mu_);
  sub_ = s;
  topic_ = topic;
  log_.line(std::string("subscribed ") + livo::roleName(role_) + " topic " + topic + " (" + datatype + ") -> " + channel_);
  return true;
}

void SensorInput::unsubscribe() {
  ros::Subscriber old;
  {
    std::lock_guard<std::mutex> lock(mu_);
    old = sub_;
    sub_ = ros::Subscriber();
    topic_.clear();
  }
  // Outside mu_: shutdown() waits for a callback in progress, which may be waiting for mu_.
  old.shutdown();
}

std::string SensorInput::topic() const {
  std::lock_guard<std::mutex> lock(mu_);
  return topic_;
}

void SensorInput::start() {
  running_ = true;
  thread_ = std::thread([this] {
    while (running_) queue_.callAvailable(ros::WallDuration(0.05));
  });
}

void SensorInput::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

void SensorInput::finish() {
  if (role_ != livo::RosRole::Imu || gate_.decided()) return;
  ready_.clear();
  gate_.finish(ready_);
  std::uint64_t published = 0;
  for (std::size_t i = 0; i < ready_.size(); ++i) {
    if (i > 0) std::this_thread::sleep_for(std::chrono::microseconds(250));  // as in onMessage()
    livo::RosPayload p(ready_[i]);
    if (publish(p)) ++published;  // a failed publish is counted as rejected, with its error
  }
  std::lock_guard<std::mutex> lock(mu_);
  // The samples held for the unit decision go out at the stop and are counted as out (and held), so the
  // summary's "in" = "out" + "rejected" + "skipped" + "dropped" holds after a stop too.
  stats_.published += published;
  stats_.held += published;
  unit_note_ = gate_.note();
}

void SensorInput::setQueueDrops(std::uint64_t drops) {
  std::lock_guard<std::mutex> lock(mu_);
  stats_.dropped = drops;
}

StreamStats SensorInput::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stats_;
}

std::string SensorInput::unitNote() const {
  std::lock_guard<std::mutex> lock(mu_);
  return unit_note_;
}

void SensorInput::decodeInto(RosWireMessage& m, const std::uint8_t* data, std::size_t size) {
  // The callback thread, inside roscpp's deserialization: `data` is roscpp's receive buffer.
  const std::string datatype = m.header("type"), md5 = m.header("md5sum");
  const livo::RosType type = livo::rosTypeOf(datatype);
  if (!livo::roleTakes(role_, type)) {
    m.reject = RosWireMessage::Reject::kType;
    m.error = "type " + datatype + " is not a " + livo::roleName(role_) + " type this bridge reads (supported: " +
              livo::rosSupportedTypes() + ")";
    return;
  }
  if (!livo::rosLayoutMatches(type, md5)) {
    m.reject = RosWireMessage::Reject::kType;
    m.error = datatype + " with definition MD5 " + md5 + " is not the layout this bridge reads (MD5 " +
              livo::rosLayoutMd5(type) + ")";
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  try {
    m.payload = decoder_.decode(type, data, size);
  } catch (const std::exception& e) {
    m.reject = RosWireMessage::Reject::kDecode;
    m.error = e.what();
  }
  m.decode_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void SensorInput::reject(const std::string& error) {
  std::uint64_t n = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    n = ++stats_.rejected;
    stats_.last_error = error;
  }
  log_.every(n, std::string(livo::roleName(role_)) + " " + topic() + ": message rejected: " + error);
}

void SensorInput::onMessage(const ros::MessageEvent<RosWireMessage const>& ev) {
  const double t_callback = wallNow();
  // roscpp's receipt time is the system clock unless the graph runs on simulated time (/use_sim_time).
  const double t_receipt = ros::Time::isSimTime() ? t_callback : ev.getReceiptTime().toSec();
  const boost::shared_ptr<RosWireMessage const> m = ev.getConstMessage();
  {
    std::lock_guard<std::mutex> lock(mu_);
    ++stats_.received;
    stats_.bytes += m->bytes;
  }
  if (m->reject != RosWireMessage::Reject::kNone) return reject(m->error);
  if (!m->payload) {
    std::lock_guard<std::mutex> lock(mu_);
    ++stats_.skipped;  // an empty scan, or one spanning more than --max-scan-span
    return;
  }
  bool ok = true;
  std::size_t published = 0;
  if (auto* imu = std::get_if<livo::ImuSample>(&*m->payload)) {
    // Held until the acceleration unit is decided, then released with the same scale as livo-convert.
    const bool was_decided = gate_.decided();
    ready_.clear();
    gate_.push(*imu, ready_);
    for (std::size_t i = 0; i < ready_.size(); ++i) {
      // A released batch goes out at most at 4 kHz: a receiver's LCM queue (30 messages by default) must
      // not overflow while it handles them.
      if (i > 0) std::this_thread::sleep_for(std::chrono::microseconds(250));
      livo::RosPayload p(ready_[i]);
      if (publish(p)) ++published;
      else ok = false;
    }
    if (!was_decided && gate_.decided()) {
      std::lock_guard<std::mutex> lock(mu_);
      unit_note_ = gate_.note();
      log_.line("IMU " + topic_ + ": " + unit_note_);
    }
  } else {
    ok = publish(*m->payload);
    published = ok ? 1 : 0;
  }
  const double latency = wallNow() - t_receipt;
  std::lock_guard<std::mutex> lock(mu_);
  stats_.published += published;
  if (published > 1) stats_.held += published;  // released at once after the unit decision: not timed
  else if (ok && published == 1) stats_.latency.add(latency);
}

bool SensorInput::publish(livo::RosPayload& p) {
  try {
    if (auto* s = std::get_if<livo::ImuSample>(&p)) lcm_.publish(channel_, livo::toMsg(*s));
    else if (auto* scan = std::get_if<livo::LidarScan>(&p)) lcm_.publish(channel_, livo::toMsg(*scan));
    else lcm_.publish(channel_, livo::toMsg(std::move(std::get<livo::Image>(p))));
  } catch (const std::exception& e) {
    reject(std::string("LCM publish failed: ") + e.what());
    return false;
  }
  return true;
}

}  // namespace livo_bridge
