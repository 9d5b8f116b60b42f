#include "livo/loop/loop_closer.hpp"

#include "livo/common/timing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
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
  loop.get("site_tile_m", site_tile_m).get("site_budget_mb", site_budget_mb);
  loop.get("relocalise_every_frames", relocalise_every_frames).get("relocalise_agree_m", relocalise_agree_m);
  loop.get("relocalise_agree_deg", relocalise_agree_deg).get("outside_map_after_m", outside_map_after_m);
  loop.get("prior_map_planes", prior_map_planes);
  loop.check(std::isfinite(site_tile_m) && site_tile_m >= 1 && site_tile_m <= 1e5, "site_tile_m", "must be in [1, 1e5] m");
  loop.check(std::isfinite(site_budget_mb) && site_budget_mb >= 0 && site_budget_mb <= 1e6, "site_budget_mb",
             "must be in [0, 1e6] MB (0: no budget)");
  loop.check(relocalise_every_frames >= 1 && relocalise_every_frames <= 1000, "relocalise_every_frames",
             "must be in [1, 1000]");
  loop.check(std::isfinite(relocalise_agree_m) && relocalise_agree_m > 0, "relocalise_agree_m", "must be > 0");
  loop.check(std::isfinite(relocalise_agree_deg) && relocalise_agree_deg > 0, "relocalise_agree_deg", "must be > 0");
  loop.check(std::isfinite(outside_map_after_m) && outside_map_after_m >= 0, "outside_map_after_m",
             "must be >= 0 (0: twice loop.descriptor_range_m)");
  if (outside_map_after_m == 0.0) outside_map_after_m = 2.0 * descriptor.max_range_m;
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
  solved_last_ = false;
  if (!unsolved_loops_) return false;
  unsolved_loops_ = false;
  Stopwatch watch;
  solved_last_ = graph_.optimize().solved;
  totals_.graph_ms += watch.elapsedMs();
  totals_.ms += watch.elapsedMs();
  totals_.solves += solved_last_;
  return solved_last_;
}

MapCorrection LoopCloser::correctionMessage(bool all, bool final) const {
  MapCorrection c;
  const int n = static_cast<int>(graph_.size());
  c.T_map_odom = graph_.correction();
  c.keyframes_total = n;
  c.first = (all || solved_last_) ? 0 : std::max(0, n - 1);
  for (int i = c.first; i < n; ++i)
    c.keyframes.push_back(KeyframePose{places_.entry(i).utime, graph_.odometryPose(i), graph_.mapPose(i)});
  c.utime = n > 0 ? places_.entry(n - 1).utime : 0;
  c.loops = loop_edges_;
  c.solves = totals_.solves;
  c.final = final;
  return c;
}

void LoopCloser::addCounters(std::map<std::string, double>& c) const {
  checks().addCounters("loop", c);
  c["loop_keyframes"] = double(graph_.size());
  c["loop_candidates"] = double(totals_.candidates);
  c["loop_graph_solves"] = double(totals_.solves);
  c["loop_points_held"] = double(points_held_);
  c["loop_point_bytes"] = double(store_.memoryBytes());
  c["loop_point_bytes_spilled"] = double(store_.spilledBytes());
  c["loop_ms_total"] = totals_.ms;
  c["loop_ms_search"] = totals_.search_ms;
  c["loop_ms_verify"] = totals_.verify_ms;
  c["loop_ms_graph"] = totals_.graph_ms;
}

std::string LoopCloser::summary() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%zu keyframes, %d candidates, %d checked, %d loops accepted, %d solves; %.0f ms in all",
                graph_.size(), totals_.candidates, checks().total(), checks().accepted, totals_.solves, totals_.ms);
  return buf;
}

LoopStep LoopCloser::add(Utime t, const Pose& T_odom_body, const std::function<std::vector<Vec3>()>& scan) {
  Stopwatch total_watch;
  const LoopStep step = addKeyframe(t, T_odom_body, scan);
  totals_.ms += total_watch.elapsedMs();
  totals_.search_ms += step.search_ms;
  totals_.verify_ms += step.verify_ms;
  totals_.graph_ms += step.graph_ms;
  totals_.candidates += step.candidates;
  totals_.solves += step.solved;
  if (step.keyframe) solved_last_ = step.solved;
  if (step.loop) loop_edges_.emplace_back(step.loop_with, step.node);
  return step;
}

LoopStep LoopCloser::addKeyframe(Utime t, const Pose& T_odom_body, const std::function<std::vector<Vec3>()>& scan) {
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
