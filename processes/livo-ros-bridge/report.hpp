// The bridge's statistics: a report every --stats seconds on stderr, the summary at exit on stdout, and
// the values of its own diagnostic status ("livo: ros bridge") once a second. Runs in the LCM thread (the
// LcmNode's counters are read there).
#pragma once

#include "bridge_log.hpp"
#include "bridge_options.hpp"
#include "bridge_stats.hpp"
#include "estimator_outputs.hpp"
#include "ros_session.hpp"
#include "sensor_input.hpp"

#include "livo/process/lcm_node.hpp"

#include <chrono>
#include <string>
#include <vector>

namespace livo_bridge {

class Reporter {
 public:
  Reporter(const BridgeOptions& opt, std::vector<SensorInput*> inputs, EstimatorOutputs& outputs, RosSession& session,
           livo::LcmNode& lcm, BridgeLog& log);
  /// Called from the LCM loop: prints the report when due and refreshes the diagnostic values.
  void poll();
  /// The statistics since start (the exit summary).
  std::string summary();

 private:
  /// One line per stream: the inputs (ROS -> LCM), then the outputs (LCM -> ROS).
  std::string streams(std::uint64_t& problems);

  const BridgeOptions& opt_;
  std::vector<SensorInput*> inputs_;
  EstimatorOutputs& outputs_;
  RosSession& session_;
  livo::LcmNode& lcm_;
  BridgeLog& log_;
  CpuMeter cpu_;
  std::uint64_t last_problems_ = 0;
  std::chrono::steady_clock::time_point next_report_, next_status_;
};

}  // namespace livo_bridge
