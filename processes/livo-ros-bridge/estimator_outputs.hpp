// LCM -> ROS: the estimator's outputs for RViz and other ROS nodes.
//   LIVO_ODOMETRY        -> <prefix>/odometry (nav_msgs/Odometry) and /tf (world -> body)
//   LIVO_REGISTERED_SCAN -> <prefix>/registered_scan (sensor_msgs/PointCloud2, world frame), and into the
//                           decimated map, published on <prefix>/map (latched) once per `map_period_s` of
//                           message time while someone listens
//   LIVO_ESTIMATOR_STATS, LIVO_MAP_STATS, odometry status and the bridge's own counters
//                        -> /diagnostics (diagnostic_msgs/DiagnosticArray), once per second
// The LCM thread decodes and validates each message (LcmNode counts and warns about rejects) and moves it
// into a bounded queue (`queue` messages per channel; when full the oldest of that channel is dropped and
// counted); a publisher thread converts and publishes. Added latency: LCM handler entry -> ROS publish
// returned.
#pragma once

#include "bridge_log.hpp"
#include "bridge_options.hpp"
#include "bridge_stats.hpp"
#include "decimated_map.hpp"

#include "livo/io/estimator_messages.hpp"
#include "livo/io/map_messages.hpp"
#include "livo/process/lcm_node.hpp"

#include <ros/node_handle.h>
#include <ros/publisher.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <variant>
#include <vector>

namespace livo_bridge {

class EstimatorOutputs {
 public:
  /// Subscribes the LCM channels on `lcm` (its handlers run in the thread that spins it).
  EstimatorOutputs(const BridgeOptions& opt, livo::LcmNode& lcm, BridgeLog& log);
  ~EstimatorOutputs();
  EstimatorOutputs(const EstimatorOutputs&) = delete;
  EstimatorOutputs& operator=(const EstimatorOutputs&) = delete;

  /// (Re-)advertises every ROS topic on `nh` (after a master restart too).
  void advertise(ros::NodeHandle& nh);
  /// The ROS topics this bridge publishes (never taken as inputs by the topic auto-detection).
  std::vector<std::string> topics() const;

  void start();
  /// Publishes what is queued, then stops the publisher thread.
  void stop();

  /// Per LCM channel.
  std::map<std::string, StreamStats> stats() const;
  /// Lines for the bridge's own diagnostic status (set by the reports).
  void setBridgeStatus(std::vector<std::pair<std::string, std::string>> values, bool warn);

 private:
  enum Kind { kOdometry = 0, kScan, kEstimatorStats, kMapStats, kKinds };
  using Value = std::variant<livo::OdometryOutput, livo::registered_scan_t, livo::EstimatorStats, livo::MapStats>;
  struct Item {
    Kind kind;
    Value value;
    std::chrono::steady_clock::time_point received;
  };
  struct Publishers {
    ros::Publisher odometry, tf, scan, map, diagnostics;
  };

  /// LCM thread: validated message into the queue.
  void push(Kind kind, Value&& v, std::chrono::steady_clock::time_point received);
  void run();
  void handle(Item& item, const Publishers& pub);
  void publishMap(const Publishers& pub, livo::Utime utime);
  void publishDiagnostics(const Publishers& pub);

  const BridgeOptions opt_;
  const std::array<std::string, kKinds> channels_;
  BridgeLog& log_;

  mutable std::mutex mu_;  // the queue, the statistics, the diagnostics' inputs
  std::condition_variable cv_;
  std::deque<Item> queue_;
  std::array<std::size_t, kKinds> queued_{};
  std::array<StreamStats, kKinds> stats_;
  bool stop_ = false;
  std::vector<std::pair<std::string, std::string>> bridge_values_;
  bool bridge_warn_ = false;

  std::mutex pub_mu_;  // the publishers: replaced by advertise(), used by the publisher thread
  Publishers pub_;

  // Publisher thread only.
  DecimatedMap map_;
  livo::Utime next_map_utime_ = 0;
  std::optional<livo::OdometryOutput> last_odometry_;
  std::optional<livo::EstimatorStats> last_estimator_stats_;
  std::optional<livo::MapStats> last_map_stats_;
  std::chrono::steady_clock::time_point last_odometry_wall_, last_map_stats_wall_, next_diagnostics_;
  std::thread thread_;
};

}  // namespace livo_bridge
