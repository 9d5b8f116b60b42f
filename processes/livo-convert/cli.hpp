// Pieces of the livo-convert command line shared by its source files.
#pragma once

#include "livo/cli/command_line.hpp"
#include "livo/datasets/rosbag.hpp"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

namespace livo_convert {

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

/// What every format takes.
struct CommonArgs {
  std::string in;  ///< DIR or BAG
  std::string out;
  bool quiet = false;
};

/// The positional input and --out / --quiet of one format's command line.
void addCommonOptions(livo::CommandLine& cl, CommonArgs& a, const std::string& input_metavar,
                      const std::string& input_help);

/// Registers the `rosbag` command's options on `cl`, filling `opt`.
void addRosbagOptions(livo::CommandLine& cl, livo::RosbagOptions& opt);

/// Runs the bag conversion, prints the summary; returns the exit code.
int runRosbag(const std::string& bag, const std::string& out, livo::RosbagOptions opt, bool quiet);

}  // namespace livo_convert
