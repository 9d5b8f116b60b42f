// livo-eval --gt GT.tum --est EST.tum [--json] [--max-dt S] [--offset S] [--scale] [--rpe-delta M]...
// Absolute trajectory error after Umeyama alignment, relative pose error over distances, matched count.
#include "livo/eval/evaluate.hpp"
#include "livo/eval/report.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <stdexcept>
#include <string>

namespace {

const char* kUsage =
    "usage: livo-eval --gt GT.tum --est EST.tum [options]\n"
    "\n"
    "Associates estimated poses with ground-truth poses by nearest timestamp, aligns the estimate onto\n"
    "the ground truth (Umeyama, SE(3) or Sim(3)), and prints the absolute trajectory error (ATE), the\n"
    "relative pose error (RPE) over travelled distances and the number of matched poses.\n"
    "Files: TUM format 't x y z qx qy qz qw' per line (t in s, pose of the body in the world frame),\n"
    "'#' comments allowed, times strictly increasing.\n"
    "\n"
    "options:\n"
    "  --gt FILE        ground-truth trajectory (required)\n"
    "  --est FILE       estimated trajectory (required)\n"
    "  --json           print one JSON object instead of the text report\n"
    "  --max-dt S       max time difference of a matched pair in seconds (default 0.01)\n"
    "  --offset S       seconds added to the estimated times before matching (default 0)\n"
    "  --scale          also estimate a scale (Sim(3) alignment, e.g. monocular); default SE(3)\n"
    "  --rpe-delta M    RPE distance in metres; repeat for several (default: 10%, 25%, 50% of the\n"
    "                   ground-truth path length rounded down to 1/2/5 x 10^k m)\n"
    "  --help           this text\n"
    "\n"
    "RPE: for each matched pose i, j is the first pose whose ground-truth path distance from i reaches\n"
    "the delta; E = (T_gt_i^-1 T_gt_j)^-1 (T_est_i^-1 T_est_j). Reported as |trans(E)| (m) and angle(E)\n"
    "(deg), and as percent of the delta and deg/m (KITTI style).\n"
    "JSON keys: ate_rmse_m ate_mean_m ate_median_m ate_max_m ate_min_m ate_std_m ate_rot_*_deg matched\n"
    "gt_poses est_poses path_length_m duration_s mean_abs_dt_s max_dt_s time_offset_s scale_estimated\n"
    "scale T_gt_est rpe[].\n"
    "Exit status: 0 on success, 1 on an evaluation error (bad file, no overlap), 2 on a usage error.\n";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

double parseNumber(const std::string& flag, const std::string& text) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(v))
    throw UsageError(flag + ": expected a number, got '" + text + "'");
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  std::string gt_path, est_path;
  bool json = false;
  livo::EvalConfig config;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw UsageError(arg + ": missing value");
        return argv[++i];
      };
      if (arg == "--help" || arg == "-h") {
        std::cout << kUsage;
        return 0;
      } else if (arg == "--gt") {
        gt_path = value();
      } else if (arg == "--est") {
        est_path = value();
      } else if (arg == "--json") {
        json = true;
      } else if (arg == "--scale") {
        config.with_scale = true;
      } else if (arg == "--max-dt") {
        config.max_dt_s = parseNumber(arg, value());
        if (config.max_dt_s < 0) throw UsageError("--max-dt: must be >= 0");
      } else if (arg == "--offset") {
        config.est_time_offset_s = parseNumber(arg, value());
      } else if (arg == "--rpe-delta") {
        const double d = parseNumber(arg, value());
        if (!(d > 0)) throw UsageError("--rpe-delta: must be > 0 m");
        config.rpe_deltas_m.push_back(d);
      } else {
        throw UsageError("unknown argument '" + arg + "'");
      }
    }
    if (gt_path.empty()) throw UsageError("--gt is required");
    if (est_path.empty()) throw UsageError("--est is required");
  } catch (const UsageError& e) {
    std::cerr << "livo-eval: " << e.what() << "\n(see livo-eval --help)\n";
    return 2;
  }

  try {
    const livo::Trajectory gt = livo::readTum(gt_path);
    const livo::Trajectory est = livo::readTum(est_path);
    livo::EvalResult result;
    try {
      result = livo::evaluate(gt, est, config);
    } catch (const std::exception& e) {
      throw std::runtime_error("--gt " + gt_path + " vs --est " + est_path + ": " + e.what());
    }
    std::cout << (json ? livo::toJson(result, config) + "\n" : livo::toText(result, config));
  } catch (const std::exception& e) {
    std::cerr << "livo-eval: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
