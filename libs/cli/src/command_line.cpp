#include "livo/cli/command_line.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <sstream>

namespace livo {

namespace {

constexpr std::size_t kHelpColumn = 26;  // option descriptions start here
constexpr std::size_t kHelpWidth = 100;  // and wrap here

std::string joinChoices(const std::vector<std::string>& values) {
  std::string s;
  for (const auto& v : values) s += (s.empty() ? "" : "|") + v;
  return s;
}

/// Shortest text that reads back as the same double ("0.01", "1e-06", "10").
std::string formatNumber(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

/// `head` padded to the description column, then `body` word-wrapped and indented to it.
std::string helpRow(std::string head, const std::string& body) {
  std::string out;
  if (head.size() + 1 >= kHelpColumn) {
    out = head + "\n";
    head.clear();
  }
  head.resize(kHelpColumn, ' ');
  std::string line = head;
  std::istringstream words(body);
  bool first = true;
  for (std::string w; words >> w; first = false) {
    if (!first && line.size() + 1 + w.size() > kHelpWidth) {
      out += line + "\n";
      line = std::string(kHelpColumn, ' ') + w;
    } else {
      line += (first ? "" : " ") + w;
    }
  }
  return out + line + "\n";
}

std::string describeInteger(std::int64_t lo, std::int64_t hi, bool lo_is_type_min, bool hi_is_type_max) {
  if (lo_is_type_min && hi_is_type_max) return "an integer";
  if (hi_is_type_max) return lo == 0 ? "a non-negative integer" : "an integer >= " + std::to_string(lo);
  if (lo_is_type_min) return "an integer <= " + std::to_string(hi);
  return "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
}

}  // namespace

// ---------------------------------------------------------------- Option

Option& Option::required() {
  is_required = true;
  return *this;
}
Option& Option::requiredUnless(std::string other) {
  is_required = true;
  required_unless = std::move(other);
  return *this;
}
Option& Option::unit(std::string u) {
  unit_ = std::move(u);
  return *this;
}
Option& Option::defaultText(std::string text) {
  default_text = std::move(text);
  custom_default = true;
  return *this;
}
Option& Option::andText(std::string metavar, std::string* dst) {
  if (kind == Kind::kFlag || kind == Kind::kPositional)
    throw std::logic_error(name + ": andText() needs an option with a value");
  second_metavar = std::move(metavar);
  set_second = [dst](const std::string& v) { *dst = v; };
  return *this;
}

// ---------------------------------------------------------------- registration

CommandLine::CommandLine(std::string program, std::string description)
    : program_(std::move(program)), description_(std::move(description)) {}

CommandLine::~CommandLine() = default;

Option& CommandLine::add(Option o) {
  if (!commands_.empty()) throw std::logic_error(program_ + ": options and sub-commands do not mix");
  if (o.kind != Option::Kind::kPositional && (o.name.rfind("--", 0) != 0 || find(o.name)))
    throw std::logic_error(program_ + ": bad or repeated option name " + o.name);
  options_.push_back(std::make_unique<Option>(std::move(o)));
  return *options_.back();
}

Option& CommandLine::text(const std::string& name, std::string* dst, const std::string& metavar,
                          const std::string& help) {
  Option o;
  o.name = name;
  o.metavar = metavar;
  o.help = help;
  o.default_text = *dst;
  o.set_text = [dst](const std::string& v) { *dst = v; };
  return add(std::move(o));
}

Option& CommandLine::choice(const std::string& name, std::string* dst, std::vector<std::string> values,
                            const std::string& help) {
  Option o;
  o.name = name;
  o.help = help;
  o.kind = Option::Kind::kChoice;
  o.default_text = *dst;
  o.choices = values;
  o.set_choice = [dst, values](std::size_t i) { *dst = values[i]; };
  return add(std::move(o));
}

Option& CommandLine::number(const std::string& name, double* dst, const std::string& metavar, const std::string& help,
                            double min, bool min_exclusive) {
  Option o;
  o.name = name;
  o.metavar = metavar;
  o.help = help;
  o.kind = Option::Kind::kNumber;
  o.num_lo = min;
  o.lo_exclusive = min_exclusive;
  o.default_text = formatNumber(*dst);
  o.set_number = [dst](double v) { *dst = v; };
  return add(std::move(o));
}

Option& CommandLine::numbers(const std::string& name, std::vector<double>* dst, const std::string& metavar,
                             const std::string& help, double min, bool min_exclusive) {
  Option o;
  o.name = name;
  o.metavar = metavar;
  o.help = help;
  o.kind = Option::Kind::kNumber;
  o.repeatable = true;
  o.num_lo = min;
  o.lo_exclusive = min_exclusive;
  o.set_number = [dst](double v) { dst->push_back(v); };
  return add(std::move(o));
}

Option& CommandLine::flag(const std::string& name, bool* dst, const std::string& help) {
  Option o;
  o.name = name;
  o.help = help;
  o.kind = Option::Kind::kFlag;
  o.set_flag = [dst]() { *dst = true; };
  return add(std::move(o));
}

Option& CommandLine::positional(const std::string& metavar, std::string* dst, const std::string& help) {
  Option o;
  o.name = metavar;
  o.metavar = metavar;
  o.help = help;
  o.kind = Option::Kind::kPositional;
  o.is_required = true;
  o.set_text = [dst](const std::string& v) { *dst = v; };
  return add(std::move(o));
}

CommandLine& CommandLine::command(const std::string& name, const std::string& description) {
  if (!options_.empty()) throw std::logic_error(program_ + ": options and sub-commands do not mix");
  auto child = std::make_unique<CommandLine>(program_ + " " + name, description);
  child->parent_ = this;
  commands_.emplace_back(name, std::move(child));
  return *commands_.back().second;
}

Option* CommandLine::find(const std::string& name) {
  for (auto& o : options_)
    if (o->name == name && o->kind != Option::Kind::kPositional) return o.get();
  return nullptr;
}
const Option* CommandLine::find(const std::string& name) const {
  return const_cast<CommandLine*>(this)->find(name);
}

CommandLine* CommandLine::findCommand(const std::string& name) const {
  for (const auto& [n, c] : commands_)
    if (n == name) return c.get();
  return nullptr;
}

bool CommandLine::given(const std::string& name) const {
  if (!chosen_.empty()) return findCommand(chosen_)->given(name);
  for (const auto& o : options_)
    if (o->name == name) return o->seen;
  return false;
}

std::string CommandLine::rootProgram() const { return parent_ ? parent_->rootProgram() : program_; }

// ---------------------------------------------------------------- parsing

CommandLine::Outcome CommandLine::parse(int argc, const char* const* argv, std::ostream& out) {
  const std::vector<std::string> args(argv + (argc > 0 ? 1 : 0), argv + argc);
  Outcome outcome = Outcome::kRun;
  parseArgs(args, 0, out, outcome);
  return outcome;
}

std::optional<int> CommandLine::parseOrExit(int argc, const char* const* argv) {
  try {
    if (parse(argc, argv, std::cout) != Outcome::kRun) return kExitOk;
  } catch (const UsageError& e) {
    std::cerr << program_ << ": " << e.what() << "\n" << hint() << "\n";
    return kExitUsage;
  }
  return std::nullopt;
}

std::string CommandLine::hint() const {
  const CommandLine* c = this;
  while (!c->chosen_.empty()) c = c->findCommand(c->chosen_);
  return "try '" + c->program_ + " --help'";
}

// One level of the line from args[first]: options and positionals, or options and a sub-command.
void CommandLine::parseArgs(const std::vector<std::string>& args, std::size_t first, std::ostream& out,
                            Outcome& outcome) {
  if (printHelpOrVersion(args, first, out, outcome)) return;
  std::size_t next_positional = 0;
  bool only_positional = false;  // after "--"
  for (std::size_t i = first; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (!only_positional && arg == "--") {
      only_positional = true;
      continue;
    }
    if (!only_positional && arg.size() > 1 && arg[0] == '-') {
      i = parseOption(args, i);
      continue;
    }
    if (!commands_.empty()) {  // the rest of the line belongs to the sub-command
      parseCommand(args, i, out, outcome);
      return;
    }
    parsePositional(next_positional++, arg);
  }
  if (!commands_.empty()) throw UsageError("missing command (" + commandNames() + ")");
  checkRequired();
}

bool CommandLine::printHelpOrVersion(const std::vector<std::string>& args, std::size_t first, std::ostream& out,
                                     Outcome& outcome) const {
  for (std::size_t j = first; j < args.size(); ++j) {
    const std::string& a = args[j];
    if (a == "--") break;
    if (a == "--help" || a == "-h") {
      out << help();
      outcome = Outcome::kHelp;
      return true;
    }
    if (a == "--version") {
      out << rootProgram() << " " << projectVersion() << "\n";
      outcome = Outcome::kVersion;
      return true;
    }
    if (a.size() > 1 && a[0] == '-') {
      const Option* o = find(a);
      if (o && o->kind != Option::Kind::kFlag) ++j;  // its value, whatever it looks like
    } else if (!commands_.empty()) {
      break;  // the rest of the line belongs to the sub-command
    }
  }
  return false;
}

std::size_t CommandLine::parseOption(const std::vector<std::string>& args, std::size_t i) {
  const std::string& arg = args[i];
  std::string name = arg, value;
  const auto eq = arg.find('=');
  const bool inline_value = arg.rfind("--", 0) == 0 && eq != std::string::npos;
  if (inline_value) name = arg.substr(0, eq), value = arg.substr(eq + 1);
  Option* o = find(name);
  if (!o) throw UsageError(unknownOptionMessage(name));
  if (o->kind == Option::Kind::kFlag) {
    if (inline_value) throw UsageError(name + ": takes no value, got '" + value + "'");
    o->set_flag();
  } else {
    if (!inline_value) {
      if (i + 1 >= args.size()) {
        const std::string what = o->kind == Option::Kind::kChoice ? joinChoices(o->choices) : o->metavar;
        throw UsageError(name + ": missing value (" + what + ")");
      }
      value = args[++i];
    }
    setValue(*o, value);
    if (o->set_second) {
      if (i + 1 >= args.size()) throw UsageError(name + ": missing value (" + o->second_metavar + ") after '" + value + "'");
      o->set_second(args[++i]);
    }
  }
  o->seen = true;
  return i;
}

std::string CommandLine::unknownOptionMessage(const std::string& name) const {
  // Names the sibling sub-commands that do take the option.
  std::string owners;
  if (parent_)
    for (const auto& [n, c] : parent_->commands_)
      if (c.get() != this && c->find(name)) owners += (owners.empty() ? "" : ", ") + n;
  return "unknown option '" + name + "'" +
         (owners.empty() ? "" : " (an option of " + owners + ", not of " + program_ + ")");
}

void CommandLine::parseCommand(const std::vector<std::string>& args, std::size_t i, std::ostream& out,
                               Outcome& outcome) {
  CommandLine* child = findCommand(args[i]);
  if (!child) throw UsageError("unknown command '" + args[i] + "' (expected " + commandNames() + ")");
  chosen_ = args[i];
  child->parseArgs(args, i + 1, out, outcome);
}

void CommandLine::parsePositional(std::size_t index, const std::string& arg) {
  Option* pos = nullptr;
  for (std::size_t k = 0, n = 0; k < options_.size() && !pos; ++k)
    if (options_[k]->kind == Option::Kind::kPositional && n++ == index) pos = options_[k].get();
  if (!pos) throw UsageError("unexpected argument '" + arg + "'");
  setValue(*pos, arg);
  pos->seen = true;
}

std::string CommandLine::commandNames() const {
  std::vector<std::string> names;
  for (const auto& c : commands_) names.push_back(c.first);
  return joinChoices(names);
}

void CommandLine::setValue(Option& o, const std::string& v) {
  const auto bad = [&](const std::string& expected) {
    throw UsageError(o.name + ": expected " + expected + ", got '" + v + "'");
  };
  switch (o.kind) {
    case Option::Kind::kText:
    case Option::Kind::kPositional:
      o.set_text(v);
      return;
    case Option::Kind::kChoice:
      for (std::size_t i = 0; i < o.choices.size(); ++i)
        if (o.choices[i] == v) return o.set_choice(i);
      bad("one of " + joinChoices(o.choices));
      return;
    case Option::Kind::kInteger: {
      const std::string expected = describeInteger(o.int_lo, o.int_hi, o.int_lo_is_type_min, o.int_hi_is_type_max);
      const std::size_t digits_from = !v.empty() && v[0] == '-' && o.int_lo < 0 ? 1 : 0;
      if (v.size() == digits_from || v.find_first_not_of("0123456789", digits_from) != std::string::npos) bad(expected);
      errno = 0;
      const long long x = std::strtoll(v.c_str(), nullptr, 10);
      if (errno == ERANGE || x < o.int_lo || x > o.int_hi) bad(expected);
      o.set_int(x);
      return;
    }
    case Option::Kind::kNumber: {
      std::string expected = "a number";
      if (std::isfinite(o.num_lo)) expected += (o.lo_exclusive ? " > " : " >= ") + formatNumber(o.num_lo);
      // Decimal notation only (strtod would also take "inf", "nan", hex and leading blanks).
      if (v.empty() || v.find_first_not_of("0123456789+-.eE") != std::string::npos) bad(expected);
      errno = 0;
      char* end = nullptr;
      const double x = std::strtod(v.c_str(), &end);
      if (end != v.c_str() + v.size() || errno == ERANGE || !std::isfinite(x)) bad(expected);
      if (x < o.num_lo || (o.lo_exclusive && x == o.num_lo)) bad(expected);
      o.set_number(x);
      return;
    }
    case Option::Kind::kFlag:
      o.set_flag();
      return;
  }
}

void CommandLine::checkRequired() const {
  for (const auto& o : options_) {
    if (!o->is_required || o->seen) continue;
    if (!o->required_unless.empty() && given(o->required_unless)) continue;
    const std::string unless = o->required_unless.empty() ? "" : " (unless " + o->required_unless + ")";
    if (o->kind == Option::Kind::kPositional) throw UsageError("missing argument " + o->metavar + unless);
    throw UsageError(o->name + " is required" + unless);
  }
}

// ---------------------------------------------------------------- help

std::string CommandLine::usageLine() const {
  std::string s = "usage: " + program_;
  if (!commands_.empty()) return s + " " + commandNames() + " ARGS [options]";
  bool optional_options = false;
  for (const auto& o : options_) {
    if (o->kind == Option::Kind::kPositional) s += o->is_required && o->required_unless.empty() ? " " + o->metavar
                                                                                                : " [" + o->metavar + "]";
  }
  for (const auto& o : options_) {
    if (o->kind == Option::Kind::kPositional) continue;
    const std::string second = o->second_metavar.empty() ? "" : " " + o->second_metavar;
    if (o->is_required && o->required_unless.empty()) s += " " + o->name + " " + o->metavar + second;
    else if (o->is_required) s += " [" + o->name + " " + o->metavar + second + "]";
    else optional_options = true;
  }
  return s + (optional_options ? " [options]" : "");
}

std::string CommandLine::optionsHelp(bool with_builtins) const {
  std::string args, opts;
  for (const auto& o : options_) {
    std::string head = "  " + o->name;
    if (o->kind == Option::Kind::kChoice) head += " " + joinChoices(o->choices);
    else if (o->kind != Option::Kind::kFlag && o->kind != Option::Kind::kPositional) head += " " + o->metavar;
    if (!o->second_metavar.empty()) head += " " + o->second_metavar;
    std::string body = o->help;
    if (o->is_required && (o->kind != Option::Kind::kPositional || !o->required_unless.empty()))
      body += o->required_unless.empty() ? " (required)" : " (required unless " + o->required_unless + ")";
    if (o->repeatable) body += " (repeatable)";
    const bool shows_default =
        !o->default_text.empty() && o->kind != Option::Kind::kFlag && o->kind != Option::Kind::kPositional;
    if (shows_default && o->custom_default && !o->unit_.empty())
      body += " [" + o->unit_ + "; default: " + o->default_text + "]";  // "[s; default: the scenario's]"
    else if (shows_default)
      body += " [default: " + o->default_text + (o->unit_.empty() ? "" : " " + o->unit_) + "]";  // "[default: 0.5 s]"
    else if (!o->unit_.empty())
      body += " [" + o->unit_ + "]";
    (o->kind == Option::Kind::kPositional ? args : opts) += helpRow(head, body);
  }
  if (with_builtins) {
    opts += helpRow("  -h, --help", "print this help and exit");
    opts += helpRow("  --version", "print '" + rootProgram() + " " + projectVersion() + "' and exit");
  }
  return (args.empty() ? "" : "arguments:\n" + args) + "options:\n" + opts;
}

std::string CommandLine::help() const {
  std::string s = usageLine() + "\n" + description_ + "\n\n";
  if (commands_.empty()) {
    s += optionsHelp(true);
  } else {
    s += "commands:\n";
    for (const auto& [name, c] : commands_) s += helpRow("  " + name, c->description_);
    s += "options:\n" + helpRow("  -h, --help", "print this help and exit (also after a command: its options)") +
         helpRow("  --version", std::string("print '") + program_ + " " + projectVersion() + "' and exit");
  }
  if (!epilog_.empty()) s += "\n" + epilog_ + (epilog_.back() == '\n' ? "" : "\n");
  for (const auto& [name, c] : commands_) s += "\n" + c->usageLine() + "\n" + c->optionsHelp(false);
  s += "\nexit status: " + std::to_string(kExitOk) + " ok, " + std::to_string(kExitRunError) + " run-time error, " +
       std::to_string(kExitUsage) + " usage or configuration error\n";
  return s;
}

}  // namespace livo
