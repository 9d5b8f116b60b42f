#include "livo/common/timing.hpp"

#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <string>

namespace livo {

double ThreadCpuStopwatch::nowMs() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

SampleSummary summarize(std::vector<double> v) {
  SampleSummary s;
  s.count = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  const std::size_t n = v.size();
  s.median = (n % 2 == 1) ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  const std::size_t rank = static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(n)));
  s.p95 = v[std::min(n - 1, rank == 0 ? 0 : rank - 1)];
  s.max = v.back();
  return s;
}

namespace {
std::uint64_t readStatusKb(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(field) + ":";
  while (std::getline(in, line)) {
    if (line.compare(0, prefix.size(), prefix) == 0) return std::stoull(line.substr(prefix.size())) * 1024ull;
  }
  return 0;
}
}  // namespace

std::uint64_t peakRssBytes() { return readStatusKb("VmHWM"); }
std::uint64_t currentRssBytes() { return readStatusKb("VmRSS"); }

double processCpuSeconds() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return 0.0;
  const auto sec = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  return sec(u.ru_utime) + sec(u.ru_stime);
}

std::string resourceSummary() {
  char buf[96];
  std::snprintf(buf, sizeof buf, "peak RSS %.2f MiB, CPU time %.2f s", bytesToMb(peakRssBytes()), processCpuSeconds());
  return buf;
}

}  // namespace livo
