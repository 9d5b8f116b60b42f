// ROS -> LCM for one role (LiDAR, IMU or camera): one roscpp subscription with its own callback queue and
// thread, so that a large scan never delays an IMU sample. roscpp's incoming queue of the subscription
// (`queue` messages; IMU `imu_queue`) is the bounded queue of this direction: it holds the serialized
// messages, drops the oldest when full (counted from roscpp's bus statistics), and a message is decoded
// (RosWireMessage: in roscpp's receive buffer, by the shared decoders) only when its turn comes. The
// decoded message is then converted (toMsg; image pixels are moved, not copied), encoded and published.
// Added latency: roscpp's receipt time -> the LCM publish returned.
#pragma once

#include "bridge_log.hpp"
#include "bridge_options.hpp"
#include "bridge_stats.hpp"
#include "ros_wire.hpp"

#include "livo/process/lcm_node.hpp"

#include <ros/callback_queue.h>
#include <ros/node_handle.h>

#include <atomic>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace livo_bridge {

class SensorInput : public WireDecoder {
 public:
  SensorInput(livo::RosRole role, const BridgeOptions& opt, livo::LcmNode& lcm, BridgeLog& log);
  ~SensorInput() override;
  SensorInput(const SensorInput&) = delete;
  SensorInput& operator=(const SensorInput&) = delete;

  livo::RosRole role() const { return role_; }
  const std::string& channel() const { return channel_; }
  /// The option naming the topic ("" = auto-detect, "none" = skip).
  const std::string& wanted() const { return wanted_; }

  /// Subscribes `topic` (published as `datatype`); false when roscpp could not register it (the master
  /// went away meanwhile).
  bool subscribe(ros::NodeHandle& nh, const std::string& topic, const std::string& datatype);
  /// Drops the subscription (before registering again with a restarted master).
  void unsubscribe();
  /// The subscribed topic ("" when none).
  std::string topic() const;

  /// Starts / stops the callback thread. stop() waits for the message in progress.
  void start();
  void stop();
  /// After stop(): publishes the IMU samples still held for the unit decision (decided with them).
  void finish();

  /// Drops in roscpp's incoming queue, from its bus statistics (TopicManager::getBusStats).
  void setQueueDrops(std::uint64_t drops);
  StreamStats stats() const;
  /// The IMU unit decision ("" before it, or for other roles).
  std::string unitNote() const;

 private:
  void decodeInto(RosWireMessage& m, const std::uint8_t* data, std::size_t size) override;
  void onMessage(const ros::MessageEvent<RosWireMessage const>& ev);
  /// Publishes one decoded message on LCM; false (and counted) when LCM refused it.
  bool publish(livo::RosPayload& p);
  void reject(const std::string& error);

  const livo::RosRole role_;
  const std::string wanted_, channel_;
  const int queue_size_;
  livo::LcmNode& lcm_;
  BridgeLog& log_;

  // Touched by the callback thread only.
  livo::RosDecoder decoder_;
  livo::ImuUnitGate gate_;
  std::vector<livo::ImuSample> ready_;

  ros::CallbackQueue queue_;
  std::thread thread_;
  std::atomic<bool> running_{false};

  mutable std::mutex mu_;  // guards what follows (read by the reports, written by the threads)
  ros::Subscriber sub_;
  std::string topic_;
  StreamStats stats_;
  std::string unit_note_;
};

}  // namespace livo_bridge
