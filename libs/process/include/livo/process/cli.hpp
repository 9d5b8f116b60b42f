// The command line of the LCM processes: --config, --lcm-url, --idle-exit, --help, plus each
// process's own options. Errors name the flag ("--idle-exit: expected a number >= 0, got 'x'").
#pragma once

#include "livo/common/config.hpp"

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace livo {

struct CliError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class CommandLine {
 public:
  /// `synopsis` follows the program name in the usage line; `description` is printed below it.
  CommandLine(std::string program, std::string synopsis, std::string description);

  /// --name VALUE (also --name=VALUE). `metavar` names the value in the help.
  void option(const std::string& name, std::string* dst, const std::string& metavar, const std::string& help);
  /// A number >= `min_value`.
  void option(const std::string& name, double* dst, const std::string& metavar, const std::string& help,
              double min_value = 0.0);
  /// --name without a value.
  void flag(const std::string& name, bool* dst, const std::string& help);
  /// Marks an option as required (checked by parse()).
  void require(const std::string& name);

  /// Parses argv. Returns false after printing the help to stdout for --help / -h (exit 0); throws
  /// CliError naming the flag for unknown options, missing values, bad numbers, positional arguments
  /// and missing required options.
  bool parse(int argc, const char* const* argv);
  std::string usage() const;
  const std::string& program() const { return program_; }

 private:
  struct Opt {
    std::string name, metavar, help;
    bool takes_value = true;
    bool required = false;
    bool seen = false;
    std::function<void(const std::string&)> set;
  };
  Opt* find(const std::string& name);

  std::string program_, synopsis_, description_;
  std::vector<Opt> opts_;
};

/// Options every LCM process takes.
struct ProcessArgs {
  std::string config;      ///< rig config (YAML); required
  std::string lcm_url;     ///< empty: $LCM_DEFAULT_URL, else kDefaultLcmUrl (resolveLcmUrl)
  double idle_exit_s = 0;  ///< > 0: exit like on SIGINT after this many seconds without any message
};

/// Adds --config (required), --lcm-url and --idle-exit to `cl`.
void addProcessOptions(CommandLine& cl, ProcessArgs& args);

/// A process reads only some sections of a shared rig config, so ConfigFile::checkAllKeysUsed() does not
/// apply. This throws ConfigError naming the first key that nobody read inside one of `sections`
/// (sections this process owns alone, e.g. {"channels", "preprocess"}): a typo there is an error.
void checkSectionsUsed(const ConfigFile& file, const std::vector<std::string>& sections);

}  // namespace livo
