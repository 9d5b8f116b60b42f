// Scoped timers, per-frame timing statistics and process memory readings.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace livo {

/// Monotonic stopwatch in milliseconds.
class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  void restart() { start_ = Clock::now(); }
  double elapsedMs() const { return std::chrono::duration<double, std::milli>(Clock::now() - start_).count(); }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

/// CPU time of the calling thread in milliseconds (CLOCK_THREAD_CPUTIME_ID): the work done, without the
/// time the thread waited for a core (what a wall-clock Stopwatch adds on a loaded machine).
class ThreadCpuStopwatch {
 public:
  ThreadCpuStopwatch() : start_(nowMs()) {}
  double elapsedMs() const { return nowMs() - start_; }
  static double nowMs();

 private:
  double start_;
};

/// Adds the elapsed milliseconds of its scope to `*sink_ms` when destroyed.
class ScopedTimer {
 public:
  explicit ScopedTimer(double* sink_ms) : sink_(sink_ms) {}
  ~ScopedTimer() {
    if (sink_) *sink_ += watch_.elapsedMs();
  }
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;

 private:
  double* sink_;
  Stopwatch watch_;
};

/// Summary of a series of samples (e.g. per-frame milliseconds).
struct SampleSummary {
  std::size_t count = 0;
  double mean = 0, median = 0, p95 = 0, max = 0;
};
/// Mean, median, 95th percentile (nearest rank) and max; zeros for an empty series.
SampleSummary summarize(std::vector<double> samples);

/// Peak resident set size of this process (VmHWM), bytes; 0 if unavailable.
std::uint64_t peakRssBytes();
/// Current resident set size (VmRSS), bytes; 0 if unavailable.
std::uint64_t currentRssBytes();
inline double bytesToMb(std::uint64_t b) { return static_cast<double>(b) / (1024.0 * 1024.0); }
/// CPU time this process has used so far (user + system, every thread), seconds; 0 if unavailable.
double processCpuSeconds();
/// "peak RSS 12.34 MiB, CPU time 5.67 s": the resource line of the processes' exit summaries.
std::string resourceSummary();

}  // namespace livo
