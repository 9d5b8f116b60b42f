// The livo-sim binary's command line: --help (defaults, exit codes), --version, usage errors naming the
// option and the value (exit 2), a scenario error (a configuration error: exit 2, naming the key).
// livo-test-bins: livo-sim
// livo-test-deps: livo_cli
#include "livo/cli/command_line.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

struct Ran {
  int rc = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Ran runSim(const std::string& args, const fs::path& dir) {
  const int status = std::system((std::string(LIVO_BINARY_DIR) + "/bin/livo-sim " + args + " > " +
                                  (dir / "out.txt").string() + " 2> " + (dir / "err.txt").string())
                                     .c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(dir / "out.txt"), slurp(dir / "err.txt")};
}

}  // namespace

TEST(LivoSimBinary, HelpVersionAndUsageErrors) {
  if (!fs::exists(std::string(LIVO_BINARY_DIR) + "/bin/livo-sim")) LIVO_SKIP() << "livo-sim not built";
  const fs::path dir = fs::temp_directory_path() / ("livo_test_sim_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  Ran r = runSim("--help", dir);
  EXPECT_EQ(r.rc, 0);
  for (const char* s : {"usage: livo-sim --out FILE --gt FILE [options]", "--random SEED", "--threads N",
                        "[default: 2]", "--duration S", "[s; default: the scenario's duration_s]",
                        "exit status: 0 ok, 1 run-time error, 2 usage or configuration error"})
    EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
  r = runSim("--version", dir);
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.out, std::string("livo-sim ") + livo::projectVersion() + "\n");

  const std::string base = "--scenario s.yaml --out o.lcm --gt g.tum";
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {" --seed 5x", "--seed: expected a non-negative integer, got '5x'"},
           {" --threads 0", "--threads: expected an integer in [1, 16], got '0'"},
           {" --duration 0", "--duration: expected a number > 0, got '0'"},
           {" --durations 3", "unknown option '--durations'"}}) {
    r = runSim(base + args, dir);
    EXPECT_EQ(r.rc, 2) << args;
    EXPECT_EQ(r.err, "livo-sim: " + message + "\ntry 'livo-sim --help'\n") << args;
  }
  r = runSim("--out o.lcm --gt g.tum", dir);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err, "livo-sim: give exactly one of --scenario FILE and --random SEED\ntry 'livo-sim --help'\n");
  r = runSim("--scenario s.yaml --random 3 --out o.lcm --gt g.tum", dir);
  EXPECT_EQ(r.rc, 2);

  // A scenario with a typo is a configuration error: exit 2, the key named, nothing written.
  std::ofstream(dir / "typo.yaml") << "duration_s: 1\nworld: {kind: room, sise_m: [8, 6, 3]}\n";
  const fs::path log = dir / "typo.lcm";
  r = runSim("--scenario " + (dir / "typo.yaml").string() + " --out " + log.string() + " --gt " +
                 (dir / "typo.tum").string() + " --quiet",
             dir);
  EXPECT_EQ(r.rc, 2) << r.err;
  EXPECT_NE(r.err.find("world.sise_m"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(log));
  fs::remove_all(dir);
}
