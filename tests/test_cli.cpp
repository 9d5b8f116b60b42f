// The command-line layer of every binary (libs/cli): each option type with good and bad values, errors
// naming the option and the value, defaults and units in the generated help, required options and
// positional arguments, sub-commands, --help / --version and what parseOrExit returns.
#include "livo/cli/command_line.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

using livo::CommandLine;
using livo::UsageError;

namespace {

enum class Fields { Auto, Xyz, Xyzi };

/// A command line with one option of every type, and the values it fills.
struct Demo {
  std::string log, config, mode = "adaptive", name;
  std::int64_t max_frames = -1;
  int threads = 2, offset = 0;
  double idle_s = 0.0, rate_hz = 10.0, duration_s = 0.0;
  std::vector<double> deltas;
  bool quiet = false, print_config = false;
  Fields fields = Fields::Auto;
  CommandLine cl{"livo-demo", "Demonstrates every option type."};

  Demo() {
    cl.positional("LOG.lcm", &log, "input log").requiredUnless("--print-config");
    cl.text("--config", &config, "CFG.yaml", "rig config").required();
    cl.text("--name", &name, "NAME", "a name");
    cl.choice("--visual-mode", &mode, {"adaptive", "all", "off"}, "when to use the camera");
    cl.choice("--fields", &fields, {{"auto", Fields::Auto}, {"xyz", Fields::Xyz}, {"xyzi", Fields::Xyzi}}, "record");
    cl.count("--max-frames", &max_frames, "N", "stop after N frames").defaultText("all");
    cl.number("--duration", &duration_s, "S", "how long", 0.0, true).unit("s").defaultText("the scenario's");
    cl.integer("--threads", &threads, "N", "worker threads", 1, 16);
    cl.integer("--offset", &offset, "K", "a signed integer");
    cl.number("--idle-exit", &idle_s, "S", "exit after S idle seconds", 0.0).unit("s");
    cl.number("--rate-hz", &rate_hz, "HZ", "scan rate", 0.0, true).unit("Hz");
    cl.numbers("--rpe-delta", &deltas, "M", "RPE distance", 0.0, true).unit("m");
    cl.flag("--quiet", &quiet, "no progress line");
    cl.flag("--print-config", &print_config, "print the configuration");
  }
  CommandLine::Outcome parse(std::vector<const char*> argv, std::ostream& out) {
    argv.insert(argv.begin(), "livo-demo");
    return cl.parse(static_cast<int>(argv.size()), argv.data(), out);
  }
  CommandLine::Outcome parse(std::vector<const char*> argv) {
    std::ostringstream out;
    return parse(std::move(argv), out);
  }
};

/// The UsageError message of parsing `argv` with a fresh Demo ("" when it parses).
std::string error(std::vector<const char*> argv) {
  Demo d;
  try {
    d.parse(std::move(argv));
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(CommandLine, GoodValuesOfEveryTypeReachTheirDestinations) {
  Demo d;
  EXPECT_EQ(d.parse({"x.lcm", "--config", "c.yaml", "--name=a=b", "--visual-mode", "off", "--fields", "xyzi",
                     "--max-frames", "5", "--threads=16", "--offset", "-3", "--idle-exit", "2.5", "--rate-hz", "1e1",
                     "--rpe-delta", "2", "--rpe-delta", "7.5", "--quiet"}),
            CommandLine::Outcome::kRun);
  EXPECT_EQ(d.log, "x.lcm");
  EXPECT_EQ(d.config, "c.yaml");
  EXPECT_EQ(d.name, "a=b");  // only the first '=' splits
  EXPECT_EQ(d.mode, "off");
  EXPECT_EQ(d.fields, Fields::Xyzi);
  EXPECT_EQ(d.max_frames, 5);
  EXPECT_EQ(d.threads, 16);
  EXPECT_EQ(d.offset, -3);
  EXPECT_DOUBLE_EQ(d.idle_s, 2.5);
  EXPECT_DOUBLE_EQ(d.rate_hz, 10.0);
  EXPECT_EQ(d.deltas, (std::vector<double>{2.0, 7.5}));
  EXPECT_TRUE(d.quiet);
  EXPECT_TRUE(d.cl.given("--quiet"));
  EXPECT_TRUE(d.cl.given("LOG.lcm"));
  EXPECT_FALSE(d.cl.given("--print-config"));

  Demo defaults;  // options left out keep their defaults
  EXPECT_EQ(defaults.parse({"--config", "c", "y.lcm"}), CommandLine::Outcome::kRun);
  EXPECT_EQ(defaults.max_frames, -1);
  EXPECT_EQ(defaults.mode, "adaptive");
  EXPECT_EQ(defaults.fields, Fields::Auto);
  EXPECT_FALSE(defaults.cl.given("--max-frames"));

  Demo negative;  // a value is the next argument whatever it looks like
  EXPECT_EQ(negative.parse({"--config", "-c", "--name", "--quiet", "--", "-odd.lcm"}), CommandLine::Outcome::kRun);
  EXPECT_EQ(negative.config, "-c");
  EXPECT_EQ(negative.name, "--quiet");
  EXPECT_FALSE(negative.quiet);
  EXPECT_EQ(negative.log, "-odd.lcm");
}

TEST(CommandLine, BadValuesNameTheOptionAndTheValue) {
  EXPECT_EQ(error({"x", "--config", "c", "--max-frames", "5x"}), "--max-frames: expected a non-negative integer, got '5x'");
  EXPECT_EQ(error({"x", "--config", "c", "--max-frames", "abc"}), "--max-frames: expected a non-negative integer, got 'abc'");
  EXPECT_EQ(error({"x", "--config", "c", "--max-frames", "-1"}), "--max-frames: expected a non-negative integer, got '-1'");
  EXPECT_EQ(error({"x", "--config", "c", "--max-frames", "+1"}), "--max-frames: expected a non-negative integer, got '+1'");
  EXPECT_EQ(error({"x", "--config", "c", "--max-frames", ""}), "--max-frames: expected a non-negative integer, got ''");
  EXPECT_EQ(error({"x", "--config", "c", "--max-frames", "99999999999999999999"}),
            "--max-frames: expected a non-negative integer, got '99999999999999999999'");
  EXPECT_EQ(error({"x", "--config", "c", "--threads", "0"}), "--threads: expected an integer in [1, 16], got '0'");
  EXPECT_EQ(error({"x", "--config", "c", "--threads", "2.0"}), "--threads: expected an integer in [1, 16], got '2.0'");
  EXPECT_EQ(error({"x", "--config", "c", "--offset", "3000000000"}), "--offset: expected an integer, got '3000000000'");
  EXPECT_EQ(error({"x", "--config", "c", "--idle-exit", "soon"}), "--idle-exit: expected a number >= 0, got 'soon'");
  EXPECT_EQ(error({"x", "--config", "c", "--idle-exit", "-1"}), "--idle-exit: expected a number >= 0, got '-1'");
  EXPECT_EQ(error({"x", "--config", "c", "--idle-exit", "inf"}), "--idle-exit: expected a number >= 0, got 'inf'");
  EXPECT_EQ(error({"x", "--config", "c", "--idle-exit", " 1"}), "--idle-exit: expected a number >= 0, got ' 1'");
  EXPECT_EQ(error({"x", "--config", "c", "--idle-exit", "1e999"}), "--idle-exit: expected a number >= 0, got '1e999'");
  EXPECT_EQ(error({"x", "--config", "c", "--rate-hz", "0"}), "--rate-hz: expected a number > 0, got '0'");
  EXPECT_EQ(error({"x", "--config", "c", "--rpe-delta", "1", "--rpe-delta", "-2"}),
            "--rpe-delta: expected a number > 0, got '-2'");
  EXPECT_EQ(error({"x", "--config", "c", "--visual-mode", "foo"}),
            "--visual-mode: expected one of adaptive|all|off, got 'foo'");
  EXPECT_EQ(error({"x", "--config", "c", "--fields", "xy"}), "--fields: expected one of auto|xyz|xyzi, got 'xy'");
  EXPECT_EQ(error({"x", "--config", "c", "--quiet=yes"}), "--quiet: takes no value, got 'yes'");
}

TEST(CommandLine, UnknownOptionsMissingValuesAndArguments) {
  EXPECT_EQ(error({"x", "--config", "c", "--bogus"}), "unknown option '--bogus'");
  EXPECT_EQ(error({"x", "--config", "c", "-q"}), "unknown option '-q'");
  EXPECT_EQ(error({"x", "--config"}), "--config: missing value (CFG.yaml)");
  EXPECT_EQ(error({"x", "--config", "c", "--visual-mode"}), "--visual-mode: missing value (adaptive|all|off)");
  EXPECT_EQ(error({"x"}), "--config is required");
  EXPECT_EQ(error({"--config", "c"}), "missing argument LOG.lcm (unless --print-config)");
  EXPECT_EQ(error({"--config", "c", "--print-config"}), "");  // LOG.lcm is not needed then
  EXPECT_EQ(error({"x", "y", "--config", "c"}), "unexpected argument 'y'");
}

TEST(CommandLine, HelpListsDefaultsUnitsRequiredAndExitCodes) {
  Demo d;
  std::ostringstream out;
  // --help wins over errors elsewhere on the line.
  EXPECT_EQ(d.parse({"--max-frames", "5x", "--help"}, out), CommandLine::Outcome::kHelp);
  const std::string help = out.str();
  EXPECT_EQ(help.rfind("usage: livo-demo [LOG.lcm] --config CFG.yaml [options]\nDemonstrates every option type.\n", 0), 0u)
      << help;
  for (const char* s : {"arguments:\n  LOG.lcm", "input log (required unless --print-config)",
                        "--config CFG.yaml", "rig config (required)", "--visual-mode adaptive|all|off",
                        "[default: adaptive]", "--fields auto|xyz|xyzi", "[default: auto]", "[default: all]",
                        "--threads N", "[default: 2]", "--idle-exit S", "[default: 0 s]", "--rate-hz HZ",
                        "[default: 10 Hz]", "RPE distance (repeatable) [m]", "how long [s; default: the scenario's]", "-h, --help", "--version",
                        "exit status: 0 ok, 1 run-time error, 2 usage or configuration error\n"})
    EXPECT_NE(help.find(s), std::string::npos) << s << "\n" << help;
  EXPECT_EQ(help.find("--name NAME              a name ["), std::string::npos) << "an empty default is not shown";

  Demo h;
  std::ostringstream short_out;
  EXPECT_EQ(h.parse({"-h"}, short_out), CommandLine::Outcome::kHelp);
  EXPECT_EQ(short_out.str(), help);
}

TEST(CommandLine, VersionPrintsProgramAndProjectVersion) {
  Demo d;
  std::ostringstream out;
  EXPECT_EQ(d.parse({"--version"}, out), CommandLine::Outcome::kVersion);
  EXPECT_EQ(out.str(), std::string("livo-demo ") + livo::projectVersion() + "\n");
  EXPECT_STRNE(livo::projectVersion(), "");
  EXPECT_NE(std::string(livo::projectVersion()).find('.'), std::string::npos);
}

TEST(CommandLine, ParseOrExitReturnsTheExitCodes) {
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  Demo ok, help, bad;
  std::vector<const char*> run = {"livo-demo", "x", "--config", "c"}, h = {"livo-demo", "--help"},
                           b = {"livo-demo", "x", "--config", "c", "--max-frames", "5x"};
  EXPECT_EQ(ok.cl.parseOrExit(int(run.size()), run.data()), std::nullopt);
  EXPECT_EQ(help.cl.parseOrExit(int(h.size()), h.data()), livo::kExitOk);
  EXPECT_EQ(bad.cl.parseOrExit(int(b.size()), b.data()), livo::kExitUsage);
  const std::string out = testing::internal::GetCapturedStdout(), err = testing::internal::GetCapturedStderr();
  EXPECT_NE(out.find("usage: livo-demo"), std::string::npos);
  // The error and a one-line hint, not the whole usage.
  EXPECT_EQ(err, "livo-demo: --max-frames: expected a non-negative integer, got '5x'\ntry 'livo-demo --help'\n");
}

TEST(CommandLine, SubCommandsHaveTheirOwnOptionsAndHelp) {
  auto make = [](CommandLine& cl, std::string& dir, std::string& out, double& rate, std::string& rig) {
    CommandLine& euroc = cl.command("euroc", "EuRoC folder");
    euroc.positional("DIR", &dir, "the folder");
    euroc.text("--out", &out, "LOG.lcm", "output log").required();
    euroc.text("--rig", &rig, "RIG.yaml", "rig config to write");
    CommandLine& kitti = cl.command("kitti", "KITTI scans");
    kitti.positional("DIR", &dir, "the folder");
    kitti.text("--out", &out, "LOG.lcm", "output log").required();
    kitti.number("--rate-hz", &rate, "HZ", "scan rate", 0.0, true).unit("Hz");
  };
  auto parse = [&](std::vector<const char*> argv, std::string* err = nullptr, std::ostream* os = nullptr) {
    CommandLine cl("livo-conv", "Converts.");
    std::string dir, out, rig;
    double rate = 10.0;
    make(cl, dir, out, rate, rig);
    argv.insert(argv.begin(), "livo-conv");
    std::ostringstream sink;
    try {
      cl.parse(int(argv.size()), argv.data(), os ? *os : sink);
    } catch (const UsageError& e) {
      if (err) *err = e.what();
      return std::string("error");
    }
    return cl.commandName() + " " + dir + " " + out + " " + std::to_string(rate) + " " + rig +
           (cl.given("--rig") ? " rig" : "");
  };
  EXPECT_EQ(parse({"kitti", "d", "--out", "o.lcm", "--rate-hz", "5"}), "kitti d o.lcm 5.000000 ");
  EXPECT_EQ(parse({"euroc", "--rig", "r.yaml", "d", "--out", "o.lcm"}), "euroc d o.lcm 10.000000 r.yaml rig");
  std::string err;
  EXPECT_EQ(parse({"euroc", "d", "--out", "o", "--rate-hz", "5"}, &err), "error");
  EXPECT_EQ(err, "unknown option '--rate-hz' (an option of kitti, not of livo-conv euroc)");
  EXPECT_EQ(parse({"bagfile", "x"}, &err), "error");
  EXPECT_EQ(err, "unknown command 'bagfile' (expected euroc|kitti)");
  EXPECT_EQ(parse({}, &err), "error");
  EXPECT_EQ(err, "missing command (euroc|kitti)");
  EXPECT_EQ(parse({"kitti", "--out", "o"}, &err), "error");
  EXPECT_EQ(err, "missing argument DIR");
  EXPECT_EQ(parse({"--out", "o", "kitti", "d"}, &err), "error");  // options follow their command
  EXPECT_EQ(err, "unknown option '--out'");

  std::ostringstream top, sub;
  parse({"--help"}, nullptr, &top);
  for (const char* s : {"usage: livo-conv euroc|kitti ARGS [options]", "commands:\n  euroc", "  kitti",
                        "usage: livo-conv euroc DIR --out LOG.lcm [options]", "usage: livo-conv kitti DIR --out LOG.lcm",
                        "[default: 10 Hz]", "exit status: 0 ok"})
    EXPECT_NE(top.str().find(s), std::string::npos) << s << "\n" << top.str();
  parse({"kitti", "--help"}, nullptr, &sub);
  EXPECT_EQ(sub.str().rfind("usage: livo-conv kitti DIR --out LOG.lcm [options]\nKITTI scans\n", 0), 0u) << sub.str();
  EXPECT_EQ(sub.str().find("euroc"), std::string::npos) << sub.str();

  // The hint names the sub-command whose options were wrong.
  CommandLine cl("livo-conv", "Converts.");
  std::string dir, out, rig;
  double rate = 10.0;
  make(cl, dir, out, rate, rig);
  std::vector<const char*> argv = {"livo-conv", "kitti", "d", "--out", "o", "--rate-hz", "fast"};
  testing::internal::CaptureStderr();
  EXPECT_EQ(cl.parseOrExit(int(argv.size()), argv.data()), livo::kExitUsage);
  EXPECT_EQ(testing::internal::GetCapturedStderr(),
            "livo-conv: --rate-hz: expected a number > 0, got 'fast'\ntry 'livo-conv kitti --help'\n");
}

TEST(CommandLine, AnOptionWithASecondWordTakesBoth) {
  double at_s = 0.0;
  std::string file;
  CommandLine cl("livo-demo", "Two words.");
  cl.number("--screenshot-at", &at_s, "S", "when", 0.0).unit("s").andText("FILE", &file);
  const auto parse = [&](std::vector<const char*> argv) {
    argv.insert(argv.begin(), "livo-demo");
    std::ostringstream out;
    return cl.parse(static_cast<int>(argv.size()), argv.data(), out);
  };
  EXPECT_EQ(parse({"--screenshot-at", "12.5", "out.png"}), CommandLine::Outcome::kRun);
  EXPECT_DOUBLE_EQ(at_s, 12.5);
  EXPECT_EQ(file, "out.png");
  parse({"--screenshot-at=3", "b.png"});
  EXPECT_DOUBLE_EQ(at_s, 3.0);
  EXPECT_EQ(file, "b.png");
  const auto error = [&](std::vector<const char*> argv) -> std::string {
    try {
      parse(std::move(argv));
    } catch (const UsageError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error({"--screenshot-at", "5"}), "--screenshot-at: missing value (FILE) after '5'");
  EXPECT_EQ(error({"--screenshot-at", "soon", "a.png"}), "--screenshot-at: expected a number >= 0, got 'soon'");
  EXPECT_NE(cl.help().find("--screenshot-at S FILE"), std::string::npos) << cl.help();
  bool flag = false;
  EXPECT_THROW(cl.flag("--flag", &flag, "f").andText("X", &file), std::logic_error);
}
