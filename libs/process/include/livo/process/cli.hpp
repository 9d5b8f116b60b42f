// What the command lines of the LCM processes share (the parser itself is libs/cli): --config,
// --lcm-url, --idle-exit and --print-config, the check of a process's own config sections, and the
// --print-config output.
#pragma once

#include "livo/cli/command_line.hpp"
#include "livo/common/config.hpp"

#include <ostream>
#include <string>
#include <vector>

namespace livo {

/// Options every LCM process takes.
struct ProcessArgs {
  std::string config;         ///< rig config (YAML); required
  std::string lcm_url;        ///< empty: $LCM_DEFAULT_URL, else kDefaultLcmUrl (resolveLcmUrl)
  double idle_exit_s = 0;     ///< > 0: exit like on SIGINT after this many seconds without any message
  bool print_config = false;  ///< print the effective configuration and exit
};

/// Adds --config (required), --lcm-url, --idle-exit and --print-config to `cl`.
void addProcessOptions(CommandLine& cl, ProcessArgs& args);

/// Adds --threads N (1..WorkerPool::kMaxThreads; default defaultThreadCount()) for the per-frame loops
/// of livo-run and livo-estimator.
void addThreadsOption(CommandLine& cl, int* threads);

/// Help text of --print-config (livo-run's too).
extern const char* const kPrintConfigHelp;

/// A process reads only some sections of a shared rig config, so ConfigFile::checkAllKeysUsed() does not
/// apply. This throws ConfigError naming the first key that nobody read inside one of `sections`
/// (sections this process owns alone, e.g. {"channels", "preprocess"}): a typo there is an error.
void checkSectionsUsed(const ConfigFile& file, const std::vector<std::string>& sections);

/// --print-config: a comment naming `program` (and `command_line`, the settings that are command-line
/// options, not config keys: "--visual-mode all"), then file.effectiveYaml(), on `os`. The text is
/// the same for a config and for its own printed configuration (no file names, no times).
void printConfig(std::ostream& os, const std::string& program, const ConfigFile& file,
                 const std::string& command_line = "");

}  // namespace livo
