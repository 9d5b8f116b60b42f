// The command line of every livo binary: typed options (string, choice among a fixed set, integer,
// non-negative integer, number with bounds, flag, repeatable number), positional arguments and
// sub-commands, with the help text (defaults and units included), --help / -h and --version generated.
//
// Errors name the option and the value ("--max-frames: expected a non-negative integer, got '5x'");
// main() prints them on stderr with a one-line hint and exits with kExitUsage:
//
//   CommandLine cl("livo-x", "Does x.");
//   cl.positional("LOG.lcm", &log, "input log");
//   cl.count("--max-frames", &max_frames, "N", "stop after N frames").defaultText("all");
//   if (const auto code = cl.parseOrExit(argc, argv)) return *code;
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace livo {

/// Exit codes of every binary of the suite (listed in every --help).
constexpr int kExitOk = 0;
constexpr int kExitRunError = 1;  ///< run-time error: bad input data, I/O, a run that failed
constexpr int kExitUsage = 2;     ///< usage or configuration error: nothing was run
/// The run finished and wrote every output, but its estimate was lost for a span (frames.csv state
/// `lost`): livo-run.
constexpr int kExitLostSpans = 3;

/// The project version (top-level CMakeLists.txt, project(VERSION)).
const char* projectVersion();

/// A bad command line; the message names the option and the value.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// One option or positional argument; the registering call returns it for the modifiers below.
class Option {
 public:
  /// The option must be given.
  Option& required();
  /// Required unless the option `other` (e.g. "--print-config") was given.
  Option& requiredUnless(std::string other);
  /// Unit of the value, shown with the default in the help ("[default: 0.01 s]").
  Option& unit(std::string u);
  /// Shown instead of the default taken from the destination ("" hides the default); with a unit the
  /// help reads "[s; default: <text>]".
  Option& defaultText(std::string text);
  /// The option's value is followed by a second word, any text, stored in `dst`
  /// ("--screenshot-at S FILE"; "--screenshot-at=S FILE" too). Not for flags.
  Option& andText(std::string metavar, std::string* dst);

 private:
  friend class CommandLine;
  enum class Kind { kText, kChoice, kInteger, kNumber, kFlag, kPositional };
  std::string name, metavar, help, unit_, default_text;
  Kind kind = Kind::kText;
  bool is_required = false, repeatable = false, seen = false;
  bool custom_default = false;  ///< default_text set by defaultText(): the unit is shown apart from it
  std::string required_unless;
  std::vector<std::string> choices;
  std::int64_t int_lo = 0, int_hi = 0;
  bool int_lo_is_type_min = false, int_hi_is_type_max = false;  ///< bounds of the type only: not in messages
  double num_lo = -std::numeric_limits<double>::infinity(), num_hi = std::numeric_limits<double>::infinity();
  bool lo_exclusive = false;
  std::function<void(const std::string&)> set_text;
  std::function<void(std::size_t)> set_choice;
  std::function<void(std::int64_t)> set_int;
  std::function<void(double)> set_number;
  std::function<void()> set_flag;
  std::string second_metavar;  ///< andText(): the second word's metavar, "" without one
  std::function<void(const std::string&)> set_second;
};

class CommandLine {
 public:
  /// `program` starts the usage line and every error message; `description` follows the usage line.
  CommandLine(std::string program, std::string description);
  ~CommandLine();
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;

  /// --name VALUE or --name=VALUE: any string.
  Option& text(const std::string& name, std::string* dst, const std::string& metavar, const std::string& help);
  /// A string among `values` (the metavar in the help is "a|b|c").
  Option& choice(const std::string& name, std::string* dst, std::vector<std::string> values, const std::string& help);
  /// A value among named constants, e.g. {{"auto", Fields::Auto}, {"xyz", Fields::Xyz}}.
  template <class E>
  Option& choice(const std::string& name, E* dst, std::vector<std::pair<std::string, E>> values,
                 const std::string& help);
  /// An integer in [lo, hi] (default: the range of T, at most that of std::int64_t).
  template <class T>
  Option& integer(const std::string& name, T* dst, const std::string& metavar, const std::string& help,
                  std::int64_t lo = lowest<T>(), std::int64_t hi = highest<T>());
  /// A non-negative integer (at most the largest T).
  template <class T>
  Option& count(const std::string& name, T* dst, const std::string& metavar, const std::string& help);
  /// A finite number >= `min` (> `min` with `min_exclusive`).
  Option& number(const std::string& name, double* dst, const std::string& metavar, const std::string& help,
                 double min = -std::numeric_limits<double>::infinity(), bool min_exclusive = false);
  /// Like number(), repeatable: every occurrence is appended.
  Option& numbers(const std::string& name, std::vector<double>* dst, const std::string& metavar,
                  const std::string& help, double min = -std::numeric_limits<double>::infinity(),
                  bool min_exclusive = false);
  /// --name without a value.
  Option& flag(const std::string& name, bool* dst, const std::string& help);
  /// The next positional argument (required unless modified), in registration order.
  Option& positional(const std::string& metavar, std::string* dst, const std::string& help);

  /// A sub-command ("livo-convert euroc DIR ..."): the first positional argument picks it and the
  /// rest of the line is parsed by the returned CommandLine. A CommandLine has options or
  /// sub-commands, not both.
  CommandLine& command(const std::string& name, const std::string& description);
  /// Text printed after the options in --help (formats, notes).
  void epilog(std::string text) { epilog_ = std::move(text); }

  enum class Outcome { kRun, kHelp, kVersion };
  /// Parses argv (argv[0] is skipped). For --help / -h and --version prints on `out` and returns
  /// kHelp / kVersion; throws UsageError for a bad command line.
  Outcome parse(int argc, const char* const* argv, std::ostream& out);
  /// parse() for main(): std::nullopt when the program should run; otherwise the exit code after
  /// printing the help or version on stdout (kExitOk) or the error and a hint on stderr (kExitUsage).
  std::optional<int> parseOrExit(int argc, const char* const* argv);

  /// True when the option (or positional metavar) was on the command line.
  bool given(const std::string& name) const;
  /// The chosen sub-command ("" when there are none).
  const std::string& commandName() const { return chosen_; }
  const std::string& program() const { return program_; }
  /// The generated help: usage line, description, arguments, options, exit codes.
  std::string help() const;
  /// "usage: <program> <required arguments> [options]".
  std::string usageLine() const;

  template <class T>
  static constexpr std::int64_t lowest() {
    return std::is_signed_v<T> ? static_cast<std::int64_t>(std::numeric_limits<T>::lowest()) : 0;
  }
  template <class T>
  static constexpr std::int64_t highest() {
    return static_cast<std::uint64_t>(std::numeric_limits<T>::max()) >
                   static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())
               ? std::numeric_limits<std::int64_t>::max()
               : static_cast<std::int64_t>(std::numeric_limits<T>::max());
  }

 private:
  Option& add(Option o);
  Option* find(const std::string& name);
  const Option* find(const std::string& name) const;
  CommandLine* findCommand(const std::string& name) const;
  void parseArgs(const std::vector<std::string>& args, std::size_t first, std::ostream& out, Outcome& outcome);
  /// --help / -h / --version anywhere on this level (before "--") win over errors elsewhere on the line:
  /// prints, sets `outcome` and returns true.
  bool printHelpOrVersion(const std::vector<std::string>& args, std::size_t first, std::ostream& out,
                          Outcome& outcome) const;
  /// The option at args[i] ("--name", "--name=value" or "--name value"); returns the index of its last word.
  std::size_t parseOption(const std::vector<std::string>& args, std::size_t i);
  std::string unknownOptionMessage(const std::string& name) const;
  /// args[i] picks the sub-command, which parses the rest of the line.
  void parseCommand(const std::vector<std::string>& args, std::size_t i, std::ostream& out, Outcome& outcome);
  /// `arg` as the positional argument number `index`.
  void parsePositional(std::size_t index, const std::string& arg);
  /// "a|b|c" of the sub-commands.
  std::string commandNames() const;
  void setValue(Option& o, const std::string& value);
  void checkRequired() const;
  std::string optionsHelp(bool with_builtins) const;
  std::string hint() const;
  std::string rootProgram() const;

  std::string program_, description_, epilog_;
  std::vector<std::unique_ptr<Option>> options_;
  std::vector<std::pair<std::string, std::unique_ptr<CommandLine>>> commands_;
  CommandLine* parent_ = nullptr;
  std::string chosen_;
  const CommandLine* failed_in_ = nullptr;  ///< the (sub-)command line whose parse failed, for the hint
};

template <class E>
Option& CommandLine::choice(const std::string& name, E* dst, std::vector<std::pair<std::string, E>> values,
                            const std::string& help) {
  Option o;
  o.name = name;
  o.help = help;
  o.kind = Option::Kind::kChoice;
  for (const auto& v : values) {
    o.choices.push_back(v.first);
    if (v.second == *dst) o.default_text = v.first;
  }
  o.set_choice = [dst, values](std::size_t i) { *dst = values[i].second; };
  return add(std::move(o));
}

template <class T>
Option& CommandLine::integer(const std::string& name, T* dst, const std::string& metavar, const std::string& help,
                             std::int64_t lo, std::int64_t hi) {
  Option o;
  o.name = name;
  o.metavar = metavar;
  o.help = help;
  o.kind = Option::Kind::kInteger;
  o.int_lo = lo;
  o.int_hi = hi;
  o.int_lo_is_type_min = lo == lowest<T>();
  o.int_hi_is_type_max = hi == highest<T>();
  o.default_text = std::to_string(*dst);
  o.set_int = [dst](std::int64_t v) { *dst = static_cast<T>(v); };
  return add(std::move(o));
}

template <class T>
Option& CommandLine::count(const std::string& name, T* dst, const std::string& metavar, const std::string& help) {
  return integer(name, dst, metavar, help, 0, highest<T>());
}

}  // namespace livo
