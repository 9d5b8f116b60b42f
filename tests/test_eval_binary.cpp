// livo-eval binary: its JSON matches the library and the oracle; options and errors give exit codes and
// messages.
// livo-test-bins: livo-eval
// livo-test-deps: livo_cli
#include "eval_test_util.hpp"

#include "livo/cli/command_line.hpp"
#include "livo/eval/evaluate.hpp"
#include "livo/eval/report.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

using namespace livo;
using namespace livo::test;
namespace fs = std::filesystem;

// ---------------------------------------------------------------- the livo-eval binary

namespace {

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

RunResult runEval(const std::string& args) {
  const fs::path out = tempDir() / "stdout.txt", err = tempDir() / "stderr.txt";
  const std::string cmd = std::string(LIVO_BINARY_DIR) + "/bin/livo-eval " + args + " >" + out.string() +
                          " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::stringstream so, se;
  so << std::ifstream(out).rdbuf();
  se << std::ifstream(err).rdbuf();
  r.out = so.str();
  r.err = se.str();
  return r;
}

bool haveBinary() { return fs::exists(std::string(LIVO_BINARY_DIR) + "/bin/livo-eval"); }

// Minimal JSON syntax check (objects, arrays, strings without escapes, numbers, literals).
bool skipJsonValue(const std::string& s, std::size_t& i) {
  auto ws = [&] { while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i; };
  ws();
  if (i >= s.size()) return false;
  if (s[i] == '{' || s[i] == '[') {
    const char close = s[i] == '{' ? '}' : ']';
    const bool object = s[i] == '{';
    ++i;
    ws();
    if (i < s.size() && s[i] == close) return ++i, true;
    while (true) {
      if (object) {
        ws();
        if (!skipJsonValue(s, i)) return false;  // key (a string)
        ws();
        if (i >= s.size() || s[i++] != ':') return false;
      }
      if (!skipJsonValue(s, i)) return false;
      ws();
      if (i < s.size() && s[i] == ',') { ++i; continue; }
      return i < s.size() && s[i++] == close;
    }
  }
  if (s[i] == '"') {
    const std::size_t end = s.find('"', i + 1);
    if (end == std::string::npos) return false;
    i = end + 1;
    return true;
  }
  for (const char* lit : {"true", "false", "null"})
    if (s.compare(i, std::strlen(lit), lit) == 0) return i += std::strlen(lit), true;
  char* end = nullptr;
  std::strtod(s.c_str() + i, &end);
  if (end == s.c_str() + i) return false;
  i = end - s.c_str();
  return true;
}

double jsonNumber(const std::string& json, const std::string& key) {
  const std::size_t k = json.find("\"" + key + "\":");
  if (k == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + k + key.size() + 3, nullptr);
}

}  // namespace

TEST(LivoEvalBinary, JsonMatchesTheLibraryAndTheOracle) {
  if (!haveBinary()) LIVO_SKIP() << "build the livo-eval target first (" << LIVO_BINARY_DIR << "/bin)";
  const Trajectory gt = syntheticTrajectory();
  const double sigma = 0.03;
  const std::string gt_path = writeTrajectory("e2e_gt.tum", gt);
  for (bool with_scale : {false, true}) {
    const Trajectory est = perturb(gt, {knownTransform(with_scale ? 0.5 : 1.0), sigma, 0.0, 9});
    const std::string est_path = writeTrajectory("e2e_est.tum", est);
    const RunResult run =
        runEval("--gt " + gt_path + " --est " + est_path + " --json" + (with_scale ? " --scale" : ""));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const std::string& json = run.out;
    std::size_t i = 0;
    ASSERT_TRUE(skipJsonValue(json, i)) << json;
    EXPECT_EQ(json.substr(i), "\n") << "one JSON object on one line";
    EXPECT_EQ(json.front(), '{');

    EvalConfig config;
    config.with_scale = with_scale;
    const EvalResult lib = evaluate(readTum(gt_path), readTum(est_path), config);
    EXPECT_NEAR(jsonNumber(json, "ate_rmse_m"), lib.ate.translation_m.rmse, 1e-8);
    EXPECT_NEAR(jsonNumber(json, "ate_mean_m"), lib.ate.translation_m.mean, 1e-8);
    EXPECT_NEAR(jsonNumber(json, "ate_median_m"), lib.ate.translation_m.median, 1e-8);
    EXPECT_NEAR(jsonNumber(json, "ate_max_m"), lib.ate.translation_m.max, 1e-8);
    EXPECT_NEAR(jsonNumber(json, "path_length_m"), lib.path_length_m, 1e-6);
    EXPECT_EQ(jsonNumber(json, "matched"), double(gt.size()));
    EXPECT_NEAR(jsonNumber(json, "ate_rmse_m"), sigma * std::sqrt(3.0), 0.05 * sigma * std::sqrt(3.0));
    EXPECT_NEAR(jsonNumber(json, "scale"), with_scale ? 2.0 : 1.0, 2e-3);
    EXPECT_NE(json.find("\"rpe\": [{\"delta_m\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"T_gt_est\": ["), std::string::npos) << json;
  }
}

TEST(LivoEvalBinary, OptionsAndErrorsGiveExitCodesAndMessages) {
  if (!haveBinary()) LIVO_SKIP() << "build the livo-eval target first (" << LIVO_BINARY_DIR << "/bin)";
  const Trajectory gt = syntheticTrajectory();
  const std::string gt_path = writeTrajectory("cli_gt.tum", gt);

  RunResult r = runEval("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* s : {"--max-dt S", "[default: 0.01 s]", "--rpe-delta M", "(repeatable)", "JSON keys:",
                        "exit status: 0 ok, 1 run-time error, 2 usage or configuration error"})
    EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
  r = runEval("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, std::string("livo-eval ") + livo::projectVersion() + "\n");
  r = runEval("--gt " + gt_path + " --est " + gt_path + " --max-dt 5x");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "livo-eval: --max-dt: expected a number >= 0, got '5x'\ntry 'livo-eval --help'\n");

  // Text report with explicit RPE distances and a time offset.
  Trajectory late = gt;
  for (StampedPose& s : late) s.t += 0.023;
  const std::string late_path = writeTrajectory("cli_late.tum", late);
  r = runEval("--gt " + gt_path + " --est " + late_path + " --offset -0.023 --rpe-delta 2 --rpe-delta 7.5");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("matched      2400 of 2400"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("RPE       2 m"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("RPE     7.5 m"), std::string::npos) << r.out;

  r = runEval("--gt " + gt_path + " --est " + late_path);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no overlap"), std::string::npos) << r.err;
  r = runEval("--gt " + gt_path + " --est " + late_path + " --max-dt 0.03 --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(jsonNumber(r.out, "matched"), 2400.0);

  const std::string empty_path = writeText("cli_empty.tum", "");
  r = runEval("--gt " + gt_path + " --est " + empty_path + " --json");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(empty_path + ": no poses"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());

  const std::string unsorted_path = writeText("cli_unsorted.tum", "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n1.5 0 0 0 0 0 0 1\n");
  r = runEval("--gt " + unsorted_path + " --est " + gt_path);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(unsorted_path + ":3:"), std::string::npos) << r.err;

  const std::vector<std::string> usage_errors = {"--est " + gt_path,
                                                 "--gt " + gt_path + " --est " + gt_path + " --max-dt x",
                                                 "--gt " + gt_path + " --est " + gt_path + " --rpe-delta 0",
                                                 "--bogus"};
  for (const std::string& args : usage_errors) {
    r = runEval(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.err.find("livo-eval: "), std::string::npos) << args << ": " << r.err;
  }
}
