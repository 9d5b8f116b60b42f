#include "bridge_stats.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace livo_bridge {

void LatencyHistogram::add(double s) {
  ++count_;
  max_ = std::max(max_, s);
  int bin = 0;
  if (s >= kMin) bin = 1 + static_cast<int>(std::floor(std::log10(s / kMin) * kPerDecade));
  bins_[std::clamp<std::size_t>(static_cast<std::size_t>(bin), 0, bins_.size() - 1)]++;
}

void LatencyHistogram::merge(const LatencyHistogram& o) {
  for (std::size_t i = 0; i < bins_.size(); ++i) bins_[i] += o.bins_[i];
  count_ += o.count_;
  max_ = std::max(max_, o.max_);
}

double LatencyHistogram::quantile(double q) const {
  if (count_ == 0) return 0;
  const auto rank = static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < bins_.size(); ++i) {
    seen += bins_[i];
    if (seen >= std::max<std::uint64_t>(rank, 1)) {
      if (i == 0) return kMin / 2;
      if (i == bins_.size() - 1) return max_;
      return std::min(max_, kMin * std::pow(10.0, (static_cast<double>(i) - 0.5) / kPerDecade));
    }
  }
  return max_;
}

std::string StreamStats::describe() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%llu in, %llu out, %llu rejected, %llu skipped, %llu dropped",
                static_cast<unsigned long long>(received), static_cast<unsigned long long>(published),
                static_cast<unsigned long long>(rejected), static_cast<unsigned long long>(skipped),
                static_cast<unsigned long long>(dropped));
  std::string s = buf;
  if (held > 0) s += " (" + std::to_string(held) + " held for the IMU unit decision, not timed)";
  if (latency.count() > 0) {
    std::snprintf(buf, sizeof buf, "; added latency median %.3f ms, p99 %.3f ms, max %.3f ms",
                  1e3 * latency.quantile(0.5), 1e3 * latency.quantile(0.99), 1e3 * latency.max());
    s += buf;
  }
  if (!last_error.empty()) s += "; last error: " + last_error;
  return s;
}

double CpuMeter::cpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  auto sec = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return sec(u.ru_utime) + sec(u.ru_stime);
}

double CpuMeter::wallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

CpuMeter::CpuMeter() : cpu0_(cpuSeconds()), wall0_(wallSeconds()), cpu_last_(cpu0_), wall_last_(wall0_) {}

double CpuMeter::percentSinceLast() {
  const double c = cpuSeconds(), w = wallSeconds();
  const double pct = w > wall_last_ ? 100.0 * (c - cpu_last_) / (w - wall_last_) : 0.0;
  cpu_last_ = c;
  wall_last_ = w;
  return pct;
}

double CpuMeter::percentTotal() const {
  const double w = wallSeconds();
  return w > wall0_ ? 100.0 * (cpuSeconds() - cpu0_) / (w - wall0_) : 0.0;
}

}  // namespace livo_bridge
