// What the bridge measures about itself: the latency it adds per message (a histogram of fixed size, so
// that a long run keeps constant memory), message counters per direction and channel, and CPU use.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace livo_bridge {

/// Latencies from 1 us to 100 s in logarithmic bins (40 per decade: a quantile is good to ~3 %).
class LatencyHistogram {
 public:
  void add(double seconds);
  void merge(const LatencyHistogram& o);
  std::uint64_t count() const { return count_; }
  /// The q-quantile (0..1) in seconds, as the geometric middle of its bin; 0 when empty.
  double quantile(double q) const;
  double max() const { return max_; }

 private:
  static constexpr int kPerDecade = 40, kDecades = 8;
  static constexpr double kMin = 1e-6;
  std::array<std::uint64_t, kPerDecade * kDecades + 2> bins_{};  ///< [0]: below kMin, [last]: above
  std::uint64_t count_ = 0;
  double max_ = 0;
};

/// Counters of one bridged stream (a ROS topic -> an LCM channel, or an LCM channel -> ROS topics).
struct StreamStats {
  std::uint64_t received = 0;   ///< messages that reached the bridge's code
  std::uint64_t published = 0;  ///< messages sent on the other side
  std::uint64_t rejected = 0;   ///< wrong type or layout, failed decoding or validation
  std::uint64_t skipped = 0;    ///< left out by a documented rule (empty scan, scan span too long; before
                                ///< the first ROS registration, the estimator outputs)
  std::uint64_t dropped = 0;    ///< lost in a full queue (roscpp's incoming queue, or the bridge's own)
  std::uint64_t held = 0;       ///< IMU samples held for the unit decision, then published (not timed)
  std::uint64_t bytes = 0;      ///< serialized bytes received
  LatencyHistogram latency;     ///< receipt -> handed to the other middleware
  std::string last_error;

  /// "412 in, 412 out, 0 rejected, 0 skipped, 0 dropped; latency median 0.12 ms, p99 0.40 ms, max 1.3 ms".
  std::string describe() const;
};

/// Process CPU time (user + system) against wall time since the previous call.
class CpuMeter {
 public:
  CpuMeter();
  /// Percent of one core since the previous call (or since construction).
  double percentSinceLast();
  /// Percent of one core since construction.
  double percentTotal() const;

 private:
  static double cpuSeconds();
  static double wallSeconds();
  double cpu0_, wall0_, cpu_last_, wall_last_;
};

}  // namespace livo_bridge
