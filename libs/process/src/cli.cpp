#include "livo/process/cli.hpp"

#include "livo/io/channels.hpp"

#include <cmath>
#include <iostream>
#include <sstream>

namespace livo {

CommandLine::CommandLine(std::string program, std::string synopsis, std::string description)
    : program_(std::move(program)), synopsis_(std::move(synopsis)), description_(std::move(description)) {}

CommandLine::Opt* CommandLine::find(const std::string& name) {
  for (auto& o : opts_)
    if (o.name == name) return &o;
  return nullptr;
}

void CommandLine::option(const std::string& name, std::string* dst, const std::string& metavar,
                         const std::string& help) {
  opts_.push_back(Opt{name, metavar, help, true, false, false, [dst](const std::string& v) { *dst = v; }});
}

void CommandLine::option(const std::string& name, double* dst, const std::string& metavar, const std::string& help,
                         double min_value) {
  opts_.push_back(Opt{name, metavar, help, true, false, false, [dst, name, min_value](const std::string& v) {
                        std::size_t used = 0;
                        double x = 0;
                        try {
                          x = std::stod(v, &used);
                        } catch (const std::exception&) {
                          used = 0;
                        }
                        if (used != v.size() || v.empty() || !std::isfinite(x) || x < min_value) {
                          std::ostringstream os;
                          os << name << ": expected a number >= " << min_value << ", got '" << v << "'";
                          throw CliError(os.str());
                        }
                        *dst = x;
                      }});
}

void CommandLine::flag(const std::string& name, bool* dst, const std::string& help) {
  opts_.push_back(Opt{name, "", help, false, false, false, [dst](const std::string&) { *dst = true; }});
}

void CommandLine::require(const std::string& name) {
  Opt* o = find(name);
  if (!o) throw std::logic_error("CommandLine::require: no option " + name);
  o->required = true;
}

bool CommandLine::parse(int argc, const char* const* argv) {
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << usage();
      return false;
    }
    if (arg.rfind("--", 0) != 0) throw CliError("unexpected argument '" + arg + "'");
    std::string value;
    bool inline_value = false;
    if (const auto eq = arg.find('='); eq != std::string::npos) {
      value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
      inline_value = true;
    }
    Opt* o = find(arg);
    if (!o) throw CliError("unknown option " + arg);
    if (o->takes_value) {
      if (!inline_value) {
        if (i + 1 >= argc) throw CliError(arg + " needs a value (" + o->metavar + ")");
        value = argv[++i];
      }
    } else if (inline_value) {
      throw CliError(arg + " takes no value");
    }
    o->set(value);
    o->seen = true;
  }
  for (const auto& o : opts_)
    if (o.required && !o.seen) throw CliError(o.name + " is required");
  return true;
}

std::string CommandLine::usage() const {
  std::ostringstream os;
  os << "usage: " << program_ << " " << synopsis_ << "\n" << description_ << "\noptions:\n";
  for (const auto& o : opts_) {
    std::string head = "  " + o.name + (o.takes_value ? " " + o.metavar : "");
    if (head.size() < 26) head.resize(26, ' ');
    else head += "\n" + std::string(26, ' ');
    os << head << o.help << (o.required ? " (required)" : "") << "\n";
  }
  os << "  --help                  this text\n";
  return os.str();
}

void addProcessOptions(CommandLine& cl, ProcessArgs& args) {
  cl.option("--config", &args.config, "CFG.yaml", "rig config (channels, sensor and module sections)");
  cl.require("--config");
  cl.option("--lcm-url", &args.lcm_url, "URL",
            std::string("LCM URL (default: $LCM_DEFAULT_URL, else ") + kDefaultLcmUrl + ")");
  cl.option("--idle-exit", &args.idle_exit_s, "S",
            "exit as on SIGINT after S seconds without any message (0: never; for tests and batch runs)");
}

void checkSectionsUsed(const ConfigFile& file, const std::vector<std::string>& sections) {
  for (const std::string& key : file.unusedKeys())
    for (const std::string& sec : sections)
      if (key == sec || key.rfind(sec + ".", 0) == 0)
        throw ConfigError(file.name() + ": " + key + ": unknown key (not read by any module of this process)");
}

}  // namespace livo
