// The bridge's life on the ROS side, in its own thread: waits for the ROS master (never fatal), registers
// the outputs and the input subscriptions, finds the input topics (the same choice as livo-convert
// rosbag: ros_input.hpp) as they appear, and notices a master that goes away and comes back. A master
// that is away leaves the established connections running (ROS 1 nodes talk peer to peer); when it is
// back, or replaced by a new master process (another PID), every subscription and publication is
// registered again.
#pragma once

#include "bridge_log.hpp"
#include "bridge_options.hpp"
#include "estimator_outputs.hpp"
#include "sensor_input.hpp"

#include <ros/node_handle.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace livo_bridge {

class RosSession {
 public:
  RosSession(const BridgeOptions& opt, std::vector<SensorInput*> inputs, EstimatorOutputs& outputs, BridgeLog& log);
  ~RosSession();

  void start();
  void stop();

  struct Stats {
    bool master_up = false;
    std::uint64_t master_losses = 0;    ///< times the master went away
    std::uint64_t registrations = 0;    ///< times everything was registered (1 + restarts seen)
    std::uint64_t topic_problems = 0;   ///< distinct topic problems seen (wrong type, ambiguous ...)
  };
  Stats stats() const;
  /// Reads roscpp's per-subscription drop counters into the inputs (the reporting thread only).
  void collectQueueDrops();

 private:
  void run();
  /// One poll: master state, (re)registration, topic discovery.
  void poll();
  void registerAll();
  void discover();

  const BridgeOptions& opt_;
  std::vector<SensorInput*> inputs_;
  EstimatorOutputs& outputs_;
  BridgeLog& log_;
  std::unique_ptr<ros::NodeHandle> nh_;
  std::thread thread_;
  std::atomic<bool> running_{false};

  // Session thread only.
  bool ever_up_ = false;
  int master_pid_ = -1;
  std::uint64_t waits_ = 0;
  std::map<std::string, std::uint64_t> problems_;  ///< problem text -> polls it was seen in
  std::map<std::string, std::uint64_t> drops_by_connection_;

  mutable std::mutex mu_;
  Stats stats_;
};

}  // namespace livo_bridge
