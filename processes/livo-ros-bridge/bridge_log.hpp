// Warnings and reports of the bridge on one stream from several threads, one whole line at a time.
#pragma once

#include "livo/process/lcm_node.hpp"

#include <cstdint>
#include <mutex>
#include <ostream>
#include <string>

namespace livo_bridge {

class BridgeLog {
 public:
  explicit BridgeLog(std::ostream& os) : os_(os) {}
  /// "livo-ros-bridge: <text>" and a newline.
  void line(const std::string& text) {
    std::lock_guard<std::mutex> lock(mu_);
    os_ << "livo-ros-bridge: " << text << "\n" << std::flush;
  }
  /// line() for the 1st..5th, 10th, 100th ... occurrence (livo::shouldWarn), with the count.
  void every(std::uint64_t occurrence, const std::string& text) {
    if (livo::shouldWarn(occurrence)) line(text + " (" + std::to_string(occurrence) + " so far)");
  }

 private:
  std::mutex mu_;
  std::ostream& os_;
};

}  // namespace livo_bridge
