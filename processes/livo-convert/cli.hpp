// Pieces of the livo-convert command line shared by its source files.
#pragma once

#include "livo/cli/command_line.hpp"
#include "livo/cli/progress.hpp"
#include "livo/datasets/rosbag.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace livo_convert {

/// The progress callback of a conversion: the shared progress line (percent of `what`, rate, time left),
/// ended when the conversion reaches its total or the callback's last copy goes.
inline livo::ProgressFn progressLine(livo::ProgressMode mode, const std::string& what) {
  auto line = std::make_shared<livo::ProgressLine>("livo-convert", what, mode);
  return [line](std::uint64_t done, std::uint64_t total) {
    if (total == 0) return;
    line->update(static_cast<double>(done) / static_cast<double>(total), static_cast<double>(done));
    if (done >= total) line->finish();
  };
}

/// What every format takes.
struct CommonArgs {
  std::string in;  ///< DIR or BAG
  std::string out;
  bool quiet = false, progress = false;
  livo::ProgressMode progressMode() const { return livo::progressMode(progress, quiet); }
};

/// The positional input and --out / --progress / --quiet of one format's command line.
void addCommonOptions(livo::CommandLine& cl, CommonArgs& a, const std::string& input_metavar,
                      const std::string& input_help);

/// Registers the `rosbag` command's options on `cl`, filling `opt`.
void addRosbagOptions(livo::CommandLine& cl, livo::RosbagOptions& opt);

/// Runs the bag conversion, prints the summary; returns the exit code.
int runRosbag(const std::string& bag, const std::string& out, livo::RosbagOptions opt, livo::ProgressMode progress);

}  // namespace livo_convert
