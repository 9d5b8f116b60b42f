// Pieces of the livo-convert command line shared by its source files.
#pragma once

#include "livo/datasets/rosbag.hpp"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

namespace livo_convert {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline double parseNumber(const std::string& flag, const std::string& s) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v) || errno == ERANGE)
    throw UsageError(flag + ": expected a number, got '" + s + "'");
  return v;
}

/// Progress on stderr: one line rewritten in place on a terminal, a line per 25 % otherwise.
class Progress {
 public:
  Progress(bool quiet, std::string what) : quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0), what_(std::move(what)) {}
  void operator()(std::uint64_t done, std::uint64_t total) {
    if (quiet_ || total == 0) return;
    const int pct = static_cast<int>(100 * done / total);
    const int step = tty_ ? 1 : 25;
    if (pct / step == last_ / step && done != total) return;
    last_ = pct;
    std::fprintf(stderr, "%slivo-convert: %llu/%llu %s (%d%%)%s", tty_ ? "\r" : "",
                 static_cast<unsigned long long>(done), static_cast<unsigned long long>(total), what_.c_str(), pct,
                 tty_ && done != total ? "" : "\n");
  }

 private:
  bool quiet_, tty_;
  std::string what_;
  int last_ = -1;
};

/// Parses the rosbag-only option args[i] (and its value, advancing i); false when it is not one.
bool parseRosbagOption(const std::vector<std::string>& args, std::size_t& i, livo::RosbagOptions& opt);

/// Runs the bag conversion, prints the summary; returns the exit code.
int runRosbag(const std::string& bag, const std::string& out, livo::RosbagOptions opt, bool quiet);

}  // namespace livo_convert
