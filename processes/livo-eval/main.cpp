// livo-eval --gt GT.tum --est EST.tum [--json] [--max-dt S] [--offset S] [--scale] [--rpe-delta M]...
//           [--align-like EST_REF --align-like-gt GT_REF]
// Absolute trajectory error after Umeyama alignment, relative pose error over distances, matched count.
#include "livo/cli/command_line.hpp"
#include "livo/eval/evaluate.hpp"
#include "livo/eval/report.hpp"

#include <exception>
#include <iostream>
#include <stdexcept>
#include <string>

namespace {

const char* kDescription =
    "Associates estimated poses with ground-truth poses by nearest timestamp, aligns the estimate onto\n"
    "the ground truth (Umeyama, SE(3) or Sim(3)), and prints the absolute trajectory error (ATE), the\n"
    "relative pose error (RPE) over travelled distances and the number of matched poses.\n"
    "Files: TUM format 't x y z qx qy qz qw' per line (t in s, pose of the body in the world frame),\n"
    "'#' comments allowed, times strictly increasing.";

const char* kEpilog =
    "RPE: for each matched pose i, j is the first pose whose ground-truth path distance from i reaches\n"
    "the delta; E = (T_gt_i^-1 T_gt_j)^-1 (T_est_i^-1 T_est_j). Reported as |trans(E)| (m) and angle(E)\n"
    "(deg), and as percent of the delta and deg/m (KITTI style).\n"
    "JSON keys: ate_rmse_m ate_mean_m ate_median_m ate_max_m ate_min_m ate_std_m ate_rot_*_deg matched\n"
    "gt_poses est_poses path_length_m duration_s mean_abs_dt_s max_dt_s time_offset_s scale_estimated\n"
    "scale T_gt_est rpe[].\n"
    "Exit status 1: an evaluation error (bad file, no overlap).";

}  // namespace

int main(int argc, char** argv) {
  std::string gt_path, est_path;
  bool json = false;
  livo::EvalConfig config;
  livo::CommandLine cl("livo-eval", kDescription);
  cl.text("--gt", &gt_path, "FILE", "ground-truth trajectory").required();
  cl.text("--est", &est_path, "FILE", "estimated trajectory").required();
  cl.flag("--json", &json, "print one JSON object instead of the text report");
  cl.number("--max-dt", &config.max_dt_s, "S", "max time difference of a matched pair", 0.0).unit("s");
  cl.number("--offset", &config.est_time_offset_s, "S", "added to the estimated times before matching").unit("s");
  cl.flag("--scale", &config.with_scale, "also estimate a scale (Sim(3) alignment, e.g. monocular); default SE(3)");
  cl.numbers("--rpe-delta", &config.rpe_deltas_m, "M", "RPE distance", 0.0, true)
      .unit("m")
      .defaultText("10%, 25%, 50% of the ground-truth path length rounded down to 1/2/5 x 10^k");
  std::string align_est, align_gt;
  cl.text("--align-like", &align_est, "EST_REF",
          "do not align --est: map it with the alignment of EST_REF onto --align-like-gt (another run in the same "
          "frame, e.g. the map-frame trajectory of the run that made a saved map), so the error includes the "
          "estimate's own frame error");
  cl.text("--align-like-gt", &align_gt, "GT_REF", "the ground truth of --align-like's run");
  cl.epilog(kEpilog);
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;

  try {
    const livo::Trajectory gt = livo::readTum(gt_path);
    const livo::Trajectory est = livo::readTum(est_path);
    livo::EvalResult result;
    if (align_est.empty() != align_gt.empty()) throw std::runtime_error("--align-like and --align-like-gt go together");
    if (!align_est.empty()) {
      try {
        config.fixed_alignment = livo::evaluate(livo::readTum(align_gt), livo::readTum(align_est), config).T_gt_est;
      } catch (const std::exception& e) {
        throw std::runtime_error("--align-like " + align_est + " --align-like-gt " + align_gt + ": " + e.what());
      }
    }
    try {
      result = livo::evaluate(gt, est, config);
    } catch (const std::exception& e) {
      throw std::runtime_error("--gt " + gt_path + " vs --est " + est_path + ": " + e.what());
    }
    std::cout << (json ? livo::toJson(result, config) + "\n" : livo::toText(result, config));
  } catch (const std::exception& e) {
    std::cerr << "livo-eval: " << e.what() << "\n";
    return livo::kExitRunError;
  }
  return livo::kExitOk;
}
