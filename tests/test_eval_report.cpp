// livo-report (scripts/livo-report, copied to build/bin): from a run directory with a known error
// against ground truth it writes the four plots and a summary whose ATE equals the oracle's; bad input
// gets a clear error. Skipped when Debian's python3-matplotlib is missing.
// livo-test-deps: livo_eval
// livo-test-bins: livo-report
#include "livo/eval/evaluate.hpp"
#include "livo/eval/tum.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

using namespace livo;
namespace fs = std::filesystem;

namespace {

const std::string kReport = std::string(LIVO_BINARY_DIR) + "/bin/livo-report";

bool haveMatplotlib() { return std::system("/usr/bin/python3 -c 'import matplotlib, numpy' >/dev/null 2>&1") == 0; }

std::string slurp(const std::string& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

int run(const std::string& cmd, std::string& out, const std::string& dir) {
  const int rc = std::system((cmd + " > " + dir + "/report.txt 2>&1").c_str());
  out = slurp(dir + "/report.txt");
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

}  // namespace

TEST(LivoReport, PlotsAndSummaryOfARunWithAKnownError) {
  if (!haveMatplotlib()) LIVO_SKIP() << "python3-matplotlib missing";
  const fs::path dir = fs::temp_directory_path() / ("livo_report_" + std::to_string(::getpid()));
  fs::create_directories(dir / "run");
  // Ground truth: a circle; estimate: rotated + shifted copy with noise (ATE after alignment = noise).
  Trajectory gt, est;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  Pose offset = Pose::Identity();
  offset.linear() = Eigen::AngleAxisd(0.7, Vec3::UnitZ()).toRotationMatrix();
  offset.translation() = Vec3(5, -2, 1);
  std::ofstream csv(dir / "run" / "frames.csv");
  csv << "t,lio_ms,vio_ms,total_ms,sigma_min,degenerate,visual_used,n_points,n_planes_matched,n_visual_points,"
         "map_bytes\n";
  for (int i = 0; i < 400; ++i) {
    const double t = 100.0 + 0.1 * i, a = 0.02 * i;
    Pose T = Pose::Identity();
    T.translation() = Vec3(10 * std::cos(a), 10 * std::sin(a), 0.1 * std::sin(3 * a));
    gt.push_back({t, T});
    Pose E = offset * T;
    E.translation() += Vec3(noise(rng), noise(rng), noise(rng));
    est.push_back({t, E});
    const bool deg = i % 50 < 5;
    csv << t << "," << 5 + i % 3 << "," << (deg ? 20 : 0) << "," << (deg ? 26 : 6) << "," << (deg ? 0.02 : 0.3) << ","
        << deg << "," << deg << ",1000,900,40," << 1000000 + 1000 * i << "\n";
  }
  csv.close();
  {
    std::ofstream g(dir / "gt.tum"), e(dir / "run" / "trajectory.tum");
    for (const auto& p : gt) writeTum(g, p);
    for (const auto& p : est) writeTum(e, p);
  }
  std::ofstream(dir / "run" / "stats.json")
      << R"({"frames": 400, "visual_mode": "adaptive", "map_mode": "hybrid", "peak_rss_mb": 50.0,
            "timing_ms": {"lio": {"mean": 6, "median": 6, "p95": 7, "max": 7},
                          "vio_per_visual_frame": {"mean": 20.5, "median": 20, "p95": 21, "max": 22}},
            "map": {"bytes": 1400000}})";
  const double oracle = evaluate(gt, est, EvalConfig{}).ate.translation_m.rmse;

  std::string out;
  ASSERT_EQ(run(kReport + " " + (dir / "run").string() + " --gt " + (dir / "gt.tum").string(), out, dir.string()), 0)
      << out;
  for (const char* png : {"trajectory.png", "timing.png", "sigma_min.png", "memory.png"}) {
    const fs::path p = dir / "run" / "report" / png;
    ASSERT_TRUE(fs::exists(p)) << png;
    EXPECT_GT(fs::file_size(p), 10000u) << png;
    EXPECT_EQ(slurp(p.string()).substr(1, 3), "PNG") << png;
  }
  const std::string md = slurp((dir / "run" / "report" / "README.md").string());
  std::ostringstream want;
  want.setf(std::ios::fixed);
  want.precision(2);
  want << "ATE RMSE (SE(3)-aligned) | " << oracle * 100 << " cm";
  EXPECT_NE(md.find(want.str()), std::string::npos) << md << "\nexpected " << want.str();
  EXPECT_NE(md.find("400 (40 with a visual update, 40 degenerate)"), std::string::npos) << md;
  EXPECT_NE(md.find("![memory](memory.png)"), std::string::npos) << md;
  EXPECT_NE(md.find("| vio ms per visual frame (mean / median / p95 / max) | 20.50 / 20.00 / 21.00 / 22.00 |"),
            std::string::npos)
      << md;

  // Bad input: a clear error naming the problem, exit code 2.
  EXPECT_EQ(run(kReport + " " + dir.string(), out, dir.string()), 2);
  EXPECT_NE(out.find("trajectory.tum missing"), std::string::npos) << out;
  std::ofstream(dir / "bad.tum") << "1 2 3\n";
  EXPECT_EQ(run(kReport + " " + (dir / "run").string() + " --gt " + (dir / "bad.tum").string(), out, dir.string()), 2);
  EXPECT_NE(out.find("bad.tum:1: expected 8 columns"), std::string::npos) << out;
  fs::remove_all(dir);
}
