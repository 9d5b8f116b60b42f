#include "livo/loop/loop_closer.hpp"

#include "livo/common/timing.hpp"

#include <cmath>
#include <filesystem>

namespace livo {

void LoopConfig::load(const ConfigNode& loop, double lidar_max_range_m, double range_noise_m, double beam_noise_deg) {
  keyframes.load(loop);
  descriptor.load(loop, lidar_max_range_m);
  search.load(loop, descriptor);
  verify.load(loop, range_noise_m, beam_noise_deg);
  verify.max_place_offset_m = descriptor.max_range_m;
  graph.load(loop);
  loop.get("keyframe_points_m", keyframe_points_m).get("verify_candidates", verify_candidates);
  loop.get("loop_spacing_m", loop_spacing_m).get("solve_sigmas", solve_sigmas);
  loop.get("points_budget_mb", points_budget_mb).get("spill_dir", spill_dir);
  loop.check(std::isfinite(points_budget_mb) && points_budget_mb >= 0 && points_budget_mb <= 1e6, "points_budget_mb",
             "must be in [0, 1e6] MB (0: no budget)");
  loop.check(spill_dir.empty() || std::filesystem::is_directory(spill_dir), "spill_dir",
             "must be an existing directory, got '" + spill_dir + "'");
  loop.check(std::isfinite(solve_sigmas) && solve_sigmas >= 0, "solve_sigmas", "must be >= 0 (0: solve at every loop)");
  loop.check(std::isfinite(loop_spacing_m) && loop_spacing_m >= 0, "loop_spacing_m", "must be >= 0");
  loop.check(std::isfinite(keyframe_points_m) && keyframe_points_m > 0 && keyframe_points_m <= 10, "keyframe_points_m",
             "must be in (0, 10] m");
  loop.check(verify_candidates >= 1 && verify_candidates <= 100, "verify_candidates", "must be in [1, 100]");
}

LoopCloser::LoopCloser(LoopConfig cfg)
    : cfg_(cfg),
      selector_(cfg_.keyframes),
      places_(cfg_.search),
      verifier_(cfg_.verify),
      graph_(cfg_.graph),
      store_(static_cast<std::size_t>(cfg_.points_budget_mb * 1024.0 * 1024.0), cfg_.spill_dir) {}

bool LoopCloser::finish() {
  if (!unsolved_loops_) return false;
  unsolved_loops_ = false;
  return graph_.optimize().solved;
}

LoopStep LoopCloser::add(Utime t, const Pose& T_odom_body, const std::function<std::vector<Vec3>()>& scan) {
  LoopStep step;
  if (!selector_.offer(T_odom_body)) return step;
  step.keyframe = true;
  const Pose K = keyframeFrame(T_odom_body);
  const Pose K_inv = K.inverse();
  std::vector<Vec3> local = scan();
  for (Vec3& p : local) p = K_inv * p;

  Stopwatch watch;
  PlaceEntry e;
  e.utime = t;
  e.path_m = selector_.pathLength();
  e.T_world_body = T_odom_body;
  e.descriptor = PlaceDescriptor::compute(local, cfg_.descriptor);
  const bool search = e.path_m - last_loop_path_m_ >= cfg_.loop_spacing_m;
  const std::vector<PlaceCandidate> cands = search ? places_.search(e.descriptor, e.path_m) : std::vector<PlaceCandidate>{};
  step.candidates = static_cast<int>(cands.size());
  step.node = graph_.addKeyframe(K);
  step.search_ms = watch.elapsedMs();

  for (const PlaceCandidate& c : cands) {
    if (step.checked >= cfg_.verify_candidates) break;
    ++step.checked;
    Stopwatch check_watch;
    const PlaceEntry& other = places_.entry(c.id);
    const Pose T_odom_rel = keyframeFrame(other.T_world_body).inverse() * K;
    step.check = verifier_.verify(store_.get(c.id).unpack(), local, c.match.yaw_rad, T_odom_rel, e.path_m - other.path_m);
    step.verify_ms += check_watch.elapsedMs();
    if (!step.check.accepted) continue;
    // The loop against the map frame as it stands: where it agrees, the solve can wait.
    const Pose err = (graph_.mapPose(c.id).inverse() * graph_.mapPose(step.node)).inverse() * step.check.T_cand_query;
    const bool agrees = err.translation().norm() < cfg_.solve_sigmas * cfg_.graph.loop_sigma_m &&
                        rotationAngle(err.linear()) < cfg_.solve_sigmas * cfg_.graph.loop_sigma_deg * M_PI / 180.0;
    graph_.addLoop(c.id, step.node, step.check.T_cand_query);
    if (agrees) {
      unsolved_loops_ = true;
    } else {
      Stopwatch graph_watch;
      step.graph = graph_.optimize();
      step.graph_ms = graph_watch.elapsedMs();
      step.solved = true;
      unsolved_loops_ = false;
    }
    step.loop = true;
    step.loop_with = c.id;
    last_loop_path_m_ = e.path_m;
    break;
  }

  places_.add(std::move(e));
  PackedPoints kept(thinPoints(local, cfg_.keyframe_points_m), cfg_.descriptor.max_range_m);
  points_held_ += kept.size();
  store_.add(std::move(kept));
  return step;
}

}  // namespace livo
