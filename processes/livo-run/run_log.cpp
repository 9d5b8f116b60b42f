#include "run_log.hpp"

#include "livo/cli/command_line.hpp"
#include "livo/cli/progress.hpp"
#include "livo/common/timing.hpp"
#include "livo/eval/tum.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/frame_row.hpp"
#include "livo/io/image_convert.hpp"
#include "livo/io/log.hpp"
#include "livo/io/run_outputs.hpp"
#include "livo/loop/relocaliser.hpp"
#include "livo/loop/prior_seeder.hpp"
#include "livo/loop/site_map.hpp"
#include "livo/process/scan_colour.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <iostream>
#include <map>
#include <optional>

namespace livo_run {

using namespace livo;

namespace {

using Counters = std::map<std::string, double>;

// frames.csv map_bytes (0 before initialisation). Hybrid mode with a memory cap: the map's O(1) byte
// estimate after its update, the value the cap is enforced on (the map recounts exactly every
// map.recount_interval updates). Without a cap the map never recounts (its estimate would use default
// bytes per item) and in global mode update() returns at once: an exact count (mapStats(), a walk of
// every structure, its time proportional to the map: ~20 ms for the street scenario's ~60 MB local map)
// every 10 frames (hybrid) or 50 frames (global), carried forward in between. Not part of the frame
// timings.
class MapBytes {
 public:
  explicit MapBytes(const Pipeline& pipeline)
      : pipeline_(pipeline),
        estimate_calibrated_(pipeline.map().mode() == MapMode::Hybrid && pipeline.map().config().capBytes() > 0),
        exact_every_(pipeline.map().mode() == MapMode::Hybrid ? 10 : 50),
        frames_since_count_(exact_every_) {}

  std::uint64_t operator()(const FrameResult& r) {
    if (!r.lio.initialized) return 0;
    if (estimate_calibrated_) return r.map.bytes;
    if (++frames_since_count_ >= exact_every_) {
      counted_ = pipeline_.mapStats().bytes;
      frames_since_count_ = 0;
    }
    return counted_;
  }

 private:
  const Pipeline& pipeline_;
  const bool estimate_calibrated_;
  const std::size_t exact_every_;
  std::size_t frames_since_count_;
  std::uint64_t counted_ = 0;
};

/// The frame's registered points (the LiDAR update's) in the odometry frame, at the frame's pose T.
std::vector<Vec3> worldPoints(const FrameResult& r, const Pose& T) {
  std::vector<Vec3> world;
  world.reserve(r.lio.points.size());
  for (const BodyPoint& bp : r.lio.points) world.push_back(T * bp.p_imu);
  return world;
}

/// --loop: every posed frame goes to the LoopCloser (its registered points on keyframes); at the end
/// trajectory_map.tum holds every frame in the map frame of the final graph (the frame's odometry pose
/// carried by the last keyframe at or before it: MapFrameTrajectory, as livo-exporter does with the
/// livo-loop process's corrections) and the loop_* counters go into stats.json.
class LoopRun {
 public:
  LoopRun(const LoopConfig& cfg, std::string save_map) : cfg_(cfg), closer_(cfg), save_map_(std::move(save_map)) {}

  void add(const Frame& frame, const FrameResult& r) {
    if (!r.lio.initialized) return;
    const Pose T = r.lio.state.pose();
    closer_.add(frame.utime, T, [&] { return worldPoints(r, T); });
    frames_.push_back({frame.utime, T});
  }

  void write(const std::string& dir) {
    closer_.finish();
    MapFrameTrajectory map;
    map.apply(closer_.correctionMessage(/*all=*/true, /*final=*/true));
    TumWriter tum(dir + "/trajectory_map.tum");
    for (const FramePose& f : frames_)
      if (const auto T_map = map.toMap(f.utime, f.T_odom)) tum.write(toSeconds(f.utime), *T_map);
    if (!save_map_.empty()) saveSiteMap(save_map_, closer_, cfg_.descriptor, cfg_.site_tile_m);
  }

  void addCounters(Counters& c) const { closer_.addCounters(c); }
  std::string summary() const {
    std::string s = "loop closure: " + closer_.summary() + "; trajectory_map.tum\n";
    if (!save_map_.empty())
      s += "site map: " + std::to_string(closer_.graph().size()) + " keyframes in " + save_map_ + " (--prior-map " +
           save_map_ + " localises in it)\n";
    return s;
  }

 private:
  struct FramePose {
    Utime utime;
    Pose T_odom;
  };
  LoopConfig cfg_;
  LoopCloser closer_;
  std::string save_map_;
  std::vector<FramePose> frames_;
};

/// --prior-map: every posed frame goes to the Relocaliser (its registered points when it tries the map);
/// at the end trajectory_map.tum holds the frames from the first relocalised one on, each carried into
/// the site map's frame by the last anchor at or before it, and the reloc_* counters go into stats.json.
class PriorMapRun {
 public:
  PriorMapRun(const LoopConfig& cfg, const std::string& dir, Pipeline& pipeline)
      : cfg_(cfg), site_(dir, cfg.site_budget_mb, cfg.descriptor), reloc_(cfg, site_), seeder_(site_, cfg),
        pipeline_(pipeline) {}

  /// Returns what to tell the user about this frame ("" when nothing).
  std::string add(const Frame& frame, const FrameResult& r) {
    if (first_frame_ < 0) first_frame_ = frame.utime;
    if (!r.lio.initialized) return {};
    const Pose T = r.lio.state.pose();
    const RelocaliseStep st = reloc_.add(frame.utime, T, [&] { return worldPoints(r, T); });
    frames_.push_back({frame.utime, T});
    if (cfg_.prior_map_planes && reloc_.localised())
      pipeline_.insertPriorPoints(seeder_.pointsNear(reloc_.correction(), T.translation()));
    char buf[200];
    if (st.localised_now) {
      std::snprintf(buf, sizeof buf, "livo-run: localised in the site map at t=%.3f s (map keyframe %d)",
                    toSeconds(frame.utime), st.map_keyframe);
      return buf;
    }
    if (st.back_in_map) {
      std::snprintf(buf, sizeof buf, "livo-run: back in the site map at t=%.3f s (map keyframe %d)",
                    toSeconds(frame.utime), st.map_keyframe);
      return buf;
    }
    if (st.left_map) {
      std::snprintf(buf, sizeof buf,
                    "livo-run: outside the site map at t=%.3f s (no map keyframe verified for loop.outside_map_after_m "
                    "of travel): odometry only, carried by the last anchor, until it is back",
                    toSeconds(frame.utime));
      return buf;
    }
    return {};
  }

  void write(const std::string& dir) {
    MapFrameTrajectory map;
    map.apply(reloc_.anchors());
    TumWriter tum(dir + "/trajectory_map.tum");
    for (const FramePose& f : frames_)
      if (const auto T_map = map.toMap(f.utime, f.T_odom)) tum.write(toSeconds(f.utime), *T_map);
  }
  void addCounters(Counters& c) const {
    reloc_.addCounters(c);
    c["reloc_prior_keyframes_inserted"] = double(seeder_.keyframesHanded());
    c["reloc_prior_points_inserted"] = double(seeder_.pointsHanded());
    // From the log's first frame (the relocaliser counts from the first frame with a pose).
    c["reloc_time_from_first_frame_s"] = reloc_.localised() ? toSeconds(reloc_.firstLocalised() - first_frame_) : -1.0;
  }
  std::string summary() const {
    std::string s = "site map " + site_.dir() + ": " + reloc_.summary();
    if (reloc_.localised()) {
      char buf[96];
      std::snprintf(buf, sizeof buf, " (%.2f s after the log's first frame)", toSeconds(reloc_.firstLocalised() - first_frame_));
      s += buf;
    }
    return s + "; trajectory_map.tum\n";
  }

 private:
  struct FramePose {
    Utime utime;
    Pose T_odom;
  };
  LoopConfig cfg_;
  SiteMap site_;
  Relocaliser reloc_;
  PriorMapSeeder seeder_;
  Pipeline& pipeline_;
  std::vector<FramePose> frames_;
  Utime first_frame_ = -1;
};

/// What happens with each frame result: its points into map.pcd (camera gray where an image saw the
/// point) and map.bt (OctoMap from the scan rays), its frames.csv / trajectory.tum row, the
/// initialisation message, the --max-frames stop.
class FrameSink {
 public:
  FrameSink(const Args& args, const Config& cfg, Pipeline& pipeline, RunOutputs& outputs, Counters& counters,
            ProgressLine& progress)
      : cloud(cfg.exporter), occupancy(cfg.exporter), args_(args), cfg_(cfg), pipeline_(pipeline),
        outputs_(outputs), counters_(counters), progress_(progress), map_bytes_(pipeline) {
    if (args.loop) loop.emplace(cfg.loop, args.save_map);
    if (!args.prior_map.empty()) prior.emplace(cfg.loop, args.prior_map, pipeline);
  }

  void operator()(const Frame& frame, const FrameResult& r) {
    if (stop_) return;
    if (!args_.no_maps && r.lio.initialized && !r.lio.points.empty()) addToMaps(frame, r);
    const FrameRecord rec = record(frame, r);
    outputs_.addFrame(rec);
    if (loop) loop->add(frame, r);
    if (prior)
      if (const std::string msg = prior->add(frame, r); !msg.empty() && !args_.quiet) progress_.message(msg);
    health.addFrame(rec);
    explain(frame, r);
    if (r.lio.initialized && !announced_init_ && !args_.quiet) {
      progress_.message("livo-run: " + pipeline_.odometry().initMessage());
      announced_init_ = true;
    }
    if (r.lidarFailed()) counters_["lio_failed_frames"] += 1;
    if (r.reset_time_offset) counters_["camera_time_offset_resets"] += 1;
    if (r.visual_used) {
      counters_["visual_points_used"] += r.n_visual_points;
      counters_["visual_longterm_points_used"] += r.n_longterm_visual_points;
      counters_["visual_frames_with_longterm_points"] += r.n_longterm_visual_points > 0;
    }
    if (args_.max_frames >= 0 && static_cast<std::int64_t>(outputs_.frames()) >= args_.max_frames) stop_ = true;
  }
  bool stopped() const { return stop_; }

  MapCloud cloud;
  OccupancyMap occupancy;
  RunHealth health;
  std::optional<LoopRun> loop;  ///< with --loop
  std::optional<PriorMapRun> prior;  ///< with --prior-map
  std::string last_wait;  ///< what the initialisation waited for at the last frame without a pose

 private:
  /// While no pose comes out, or the LiDAR update keeps failing, say why once per second of log.
  void explain(const Frame& frame, const FrameResult& r) {
    if (!r.lio.initialized) {
      last_wait = pipeline_.odometry().waitMessage();
      if (first_wait_ < 0) first_wait_ = frame.utime;
      if (!args_.quiet && toSeconds(frame.utime - last_said_) >= 1.0) {
        last_said_ = frame.utime;
        char head[96];
        std::snprintf(head, sizeof head, "livo-run: no pose yet, %.1f s after the first frame: ",
                      toSeconds(frame.utime - first_wait_));
        progress_.message(head + last_wait);
      }
      return;
    }
    if (r.health.state == HealthState::Lost) {  // said at once, then every 2 s of log while it lasts
      if (lost_since_ < 0) lost_since_ = frame.utime;
      if (!args_.quiet && (lost_said_ < 0 || toSeconds(frame.utime - lost_said_) >= 2.0)) {
        lost_said_ = frame.utime;
        char head[128];
        std::snprintf(head, sizeof head, "livo-run: LOST at t %.2f s (for %.1f s): ", toSeconds(frame.utime),
                      toSeconds(frame.utime - lost_since_));
        progress_.message(head + r.health.reason);
      }
    } else if (lost_since_ >= 0) {
      if (!args_.quiet) progress_.message("livo-run: consistent again at t " + std::to_string(toSeconds(frame.utime)) +
                                          " s: " + (r.health.reason.empty() ? "ok" : r.health.reason));
      lost_since_ = lost_said_ = -1;
    }
    if (!r.lidarFailed()) {
      fail_since_ = -1;
      return;
    }
    if (fail_since_ < 0) fail_since_ = frame.utime;
    const double failing_s = toSeconds(frame.utime - fail_since_);
    if (!args_.quiet && failing_s >= 1.0 && toSeconds(frame.utime - last_said_) >= 1.0) {
      last_said_ = frame.utime;
      char msg[256];
      std::snprintf(msg, sizeof msg,
                    "livo-run: LiDAR update failing for %.1f s: %d of %d points matched a plane (%d needed)%s",
                    failing_s, r.lio.n_matched, r.lio.n_points, cfg_.pipe.lio.min_matches,
                    r.visual_used ? "; the camera carries the frame" : "; on the IMU alone");
      progress_.message(msg);
    }
  }
  Utime first_wait_ = -1, last_said_ = std::numeric_limits<Utime>::min() / 2, fail_since_ = -1;
  Utime lost_since_ = -1, lost_said_ = -1;

  void addToMaps(const Frame& frame, const FrameResult& r) {
    const Pose T_world_imu = r.lio.state.pose();
    const RegisteredScan scan =
        colourScan(frame.utime, T_world_imu, r.lio.points, pipeline_.camera(), frame.has_image ? &frame.image : nullptr,
                   cfg_.pipe.camera.T_imu_camera, cfg_.pipe.camera.scale);
    cloud.add(scan.points, scan.intensity, scan.rgb);
    occupancy.insertScan(T_world_imu * cfg_.pipe.lio.T_imu_lidar.translation(), scan.points);
  }
  FrameRecord record(const Frame& frame, const FrameResult& r) {
    FrameRecord rec;
    rec.utime = frame.utime;
    rec.has_pose = r.lio.initialized;
    rec.T_world_imu = r.lio.state.pose();
    applyStats(rec, frameStats(r, frame.utime, 0, 0));  // the row the four processes write (frame_row.hpp)
    rec.map_bytes = map_bytes_(r);
    return rec;
  }

  const Args& args_;
  const Config& cfg_;
  const Pipeline& pipeline_;
  RunOutputs& outputs_;
  Counters& counters_;
  ProgressLine& progress_;
  MapBytes map_bytes_;
  bool stop_ = false;
  bool announced_init_ = false;
};

/// Decodes and validates one log event of a sensor channel and feeds it to the pipeline. False when it
/// was not fed: another channel, the camera disabled, or a rejected message (counted).
bool feedEvent(const LogEvent& ev, const Config& cfg, Pipeline& pipeline, Counters& counters, bool quiet,
               ProgressLine& progress) {
  const MessageLimits limits{};
  if (ev.channel == cfg.channels.imu) {
    livo::imu_t m;
    ImuSample s;
    Validation v = decode(ev.data.data(), ev.data.size(), m, limits);
    if (v) v = fromMsg(m, s);
    if (!v) {
      counters["rejected_imu"] += 1;
      return false;
    }
    pipeline.addImu(s);
  } else if (ev.channel == cfg.channels.lidar) {
    livo::lidar_scan_t m;
    LidarScan s;
    std::size_t nonfinite = 0;
    Validation v = decode(ev.data.data(), ev.data.size(), m, limits);
    if (v) v = fromMsg(m, s, limits, &nonfinite);
    if (!v) {
      counters["rejected_scans"] += 1;
      if (!quiet) progress.message("livo-run: dropped a scan: " + v.error);
      return false;
    }
    counters["nonfinite_points"] += double(nonfinite);
    pipeline.addScan(s);
  } else if (ev.channel == cfg.channels.camera) {
    if (!cfg.pipe.preprocess.camera_enabled) return false;
    livo::image_t m;
    Image img, gray;
    std::string err;
    Validation v = decode(ev.data.data(), ev.data.size(), m, limits);
    if (v) v = fromMsg(std::move(m), img, limits);
    if (v && !toGray8(std::move(img), gray, &err)) v = Validation::fail(err);
    if (!v) {
      counters["rejected_images"] += 1;
      if (!quiet) progress.message("livo-run: dropped an image: " + v.error);
      return false;
    }
    pipeline.addImage(std::move(gray));
  } else {
    return false;
  }
  return true;
}

/// Step 2, the replay: every event fed, every complete frame run, the progress line (share of the log's
/// bytes read, frames and their rate, time left).
/// Returns the log error that stopped it ("" at the end of the log or at --max-frames).
std::string replay(const Args& args, const Config& cfg, LogReader& reader, Pipeline& pipeline, FrameSink& sink,
                   const RunOutputs& outputs, Counters& counters, ProgressLine& progress) {
  const auto runFrames = [&]() { pipeline.processReady([&](const Frame& f, const FrameResult& r) { sink(f, r); }); };
  const double log_bytes = double(std::max<std::uint64_t>(1, reader.fileSize()));
  std::string log_error;
  LogEvent ev;
  try {
    while (reader.next(ev)) {
      if (!feedEvent(ev, cfg, pipeline, counters, args.quiet, progress)) continue;
      runFrames();
      if (sink.stopped()) break;
      progress.update(double(reader.position()) / log_bytes, double(outputs.frames()));
    }
    if (!sink.stopped()) {
      pipeline.flush();
      runFrames();
    }
  } catch (const LogError& e) {
    log_error = e.what();  // keep everything processed so far; reported by the caller
  }
  progress.finish();
  return log_error;
}

/// The recombiner's counters as preprocess_<name> and the map's as map_<name>.
void addStatsCounters(const PreprocessStats& pst, const HybridMapCounters& mc, Counters& counters) {
  for (const auto& [k, v] : std::map<std::string, std::uint64_t>{
           {"frames", pst.frames}, {"empty_sweeps", pst.empty_sweeps}, {"images_used", pst.images_used},
           {"images_dropped", pst.imagesDropped()}, {"imu_out_of_order", pst.imu_out_of_order},
           {"imu_duplicates", pst.imu_duplicates}, {"imu_gaps", pst.imu_gaps},
           {"scans_out_of_order", pst.scans_out_of_order}, {"points_in", pst.points_in},
           {"points_nan", pst.points_nan}, {"points_emitted", pst.points_emitted},
           {"scans_in", pst.scans_in}, {"scans_empty", pst.scans_empty}, {"imu_in", pst.imu_in},
           {"images_in", pst.images_in}, {"images_invalid", pst.images_invalid},
           {"buffer_overflow_drops", pst.bufferOverflowDrops()}})
    counters["preprocess_" + k] = double(v);
  for (const auto& [k, v] : std::map<std::string, double>{
           {"slides", double(mc.slides)}, {"longterm_slides", double(mc.longterm_slides)},
           {"removed_voxels", double(mc.removed_voxels)}, {"moved_to_longterm", double(mc.moved_to_longterm)},
           {"moved_to_local", double(mc.moved_to_local)}, {"deleted_points", double(mc.deleted_points)},
           {"eviction_events", double(mc.eviction_events)}, {"evicted_longterm_points", double(mc.evicted_longterm_points)},
           {"evicted_local_voxels", double(mc.evicted_local_voxels)}, {"evicted_local_points", double(mc.evicted_local_points)},
           {"max_update_ms", mc.max_update_ms}, {"max_slide_ms", mc.max_slide_ms}})
    counters["map_" + k] = v;
}

/// Step 3, the outputs: map.pcd / map.bt, stats.json, the summary on stdout.
int writeOutputs(const Args& args, const Config& cfg, const Pipeline& pipeline, FrameSink& sink, RunOutputs& outputs,
                 Counters& counters, const std::string& log_error) {
  const PreprocessStats& pst = pipeline.recombiner().stats();
  const HybridMapStats hs = pipeline.mapStats();
  MapSummary ms;
  ms.local_voxels = hs.local_voxels;
  ms.visual_points_local = hs.visual_points_local;
  ms.visual_points_longterm = hs.visual_points_longterm;
  ms.bytes = hs.bytes;
  ms.has_parts = true;
  ms.bytes_lidar = hs.bytes_lidar;
  ms.bytes_visual_local = hs.bytes_visual_local;
  ms.bytes_visual_longterm = hs.bytes_visual_longterm;
  ms.bytes_index = hs.bytes_index;
  if (!args.no_maps) {
    sink.cloud.writePcd(args.out + "/map.pcd");
    if (cfg.exporter.octomap_enabled) sink.occupancy.writeBt(args.out + "/map.bt");
  }
  counters["map_pcd_points"] = double(sink.cloud.size());
  addStatsCounters(pst, hs.counters, counters);
  if (sink.loop) {
    sink.loop->write(args.out);
    sink.loop->addCounters(counters);
  }
  if (sink.prior) {
    sink.prior->write(args.out);
    sink.prior->addCounters(counters);
  }
  counters["map_bt_scans_dropped"] = double(sink.occupancy.scansDropped());
  counters["map_bt_scans_capped"] = double(sink.occupancy.scansCapped());
  const ImageCheckCounters& ic = pipeline.frames().imageCounters();
  counters["images_wrong_size"] = double(ic.wrong_size);
  counters["images_black"] = double(ic.black);
  counters["images_saturated"] = double(ic.saturated);
  counters["images_frozen"] = double(ic.frozen);
  counters["images_missing"] = double(ic.missing);
  const double rss = bytesToMb(peakRssBytes());
  std::map<std::string, std::string> notes{{"visual_mode", args.visual_mode}, {"map_mode", args.map_mode},
                                           {"threads", std::to_string(args.threads)},
                                           {"log", args.log}, {"config", args.config}};
  if (!log_error.empty()) notes["log_error"] = log_error;
  if (args.loop) notes["loop"] = "on";
  if (!args.prior_map.empty()) notes["prior_map"] = args.prior_map;
  if (const std::string note = sink.occupancy.capNote(); !note.empty()) notes["map_bt"] = note;
  if (!sink.health.anyPose())
    sink.health.no_pose_reason = outputs.frames() == 0 ? "no complete frame in the log (LiDAR scans with IMU samples)"
                                                        : "never initialised: " + sink.last_wait;
  outputs.writeStats(ms, rss, counters, notes, &sink.health);
  std::cout << outputs.summary(rss);
  if (sink.loop) std::cout << sink.loop->summary();
  if (sink.prior) std::cout << sink.prior->summary();
  if (!args.quiet) std::cout << "preprocessing:\n" << pst.summary() << "\n";
  std::cout << "outputs in " << args.out << "\n";
  if (!log_error.empty()) {
    std::cerr << "livo-run: error: " << log_error << " (outputs up to this point were written)\n";
    return kExitRunError;
  }
  if (!sink.health.anyPose()) {  // a run without a single pose is a failure, whatever the cause
    std::cerr << "livo-run: warning: no pose in " << outputs.frames() << " frames: " << sink.health.no_pose_reason
              << "\n";
    return kExitRunError;
  }
  if (sink.health.anyLost()) {  // every output was written; the trajectory holds spans not to be trusted
    std::cerr << "livo-run: warning: the estimate was lost " << sink.health.lost_spans << " time(s), "
              << sink.health.lost_s << " s in all from t " << sink.health.first_lost_t
              << " s (frames.csv state 'lost', with the reason); exit status " << kExitLostSpans << "\n";
    return kExitLostSpans;
  }
  return kExitOk;
}

}  // namespace

int runLog(const Args& args, const Config& cfg) {
  LogReader reader(args.log);
  RunOutputs outputs(args.out);
  Pipeline pipeline(cfg.pipe);
  Counters counters;
  ProgressLine progress("livo-run", "frames", progressMode(args.progress, args.quiet));
  FrameSink sink(args, cfg, pipeline, outputs, counters, progress);
  const std::string log_error = replay(args, cfg, reader, pipeline, sink, outputs, counters, progress);
  return writeOutputs(args, cfg, pipeline, sink, outputs, counters, log_error);
}

}  // namespace livo_run
