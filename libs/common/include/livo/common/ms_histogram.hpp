// Quantiles of durations over a whole run in bounded memory: a histogram of fixed-width bins.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace livo {

/// Durations in bins of `bin_ms` from 0 to `max_ms` (the last bin holds everything beyond). A quantile is
/// the middle of the bin where it falls, so it is exact to half a bin.
class MsHistogram {
 public:
  explicit MsHistogram(double bin_ms = 1.0, double max_ms = 10000.0)
      : bin_ms_(bin_ms), bins_(static_cast<std::size_t>(max_ms / bin_ms) + 1, 0) {}

  void add(double ms) {
    std::size_t i = 0;  // NaN and negatives count in bin 0
    if (ms > 0.0) {
      const double b = ms / bin_ms_;
      i = b < double(bins_.size() - 1) ? static_cast<std::size_t>(b) : bins_.size() - 1;
    }
    ++bins_[i];
    ++count_;
  }
  std::uint64_t count() const { return count_; }
  /// The q-quantile (0.5: median), ms; -1 when empty.
  double quantile(double q) const {
    if (count_ == 0) return -1.0;
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < bins_.size(); ++i) {
      seen += bins_[i];
      if (double(seen) >= q * double(count_)) return (double(i) + 0.5) * bin_ms_;
    }
    return double(bins_.size()) * bin_ms_;
  }

 private:
  double bin_ms_;
  std::vector<std::uint32_t> bins_;
  std::uint64_t count_ = 0;
};

}  // namespace livo
