// livo-run LOG.lcm --config CFG.yaml --out DIR [--visual-mode adaptive|all|off] [--map-mode hybrid|global]
//
// Runs the whole pipeline in one process (no network) on an LCM log, as fast as possible:
// log events -> validated structs -> frame builder (recut sweeps + IMU + image) -> odometry -> outputs.
// Writes DIR/trajectory.tum, DIR/frames.csv (map_bytes: see onFrame below), DIR/stats.json; a progress
// line on stderr and a summary on stdout. A truncated or corrupt log stops the run with an error after
// writing what was processed.
#include "livo/common/config.hpp"
#include "livo/common/timing.hpp"
#include "livo/estimation/pipeline.hpp"
#include "livo/io/channels.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/image_convert.hpp"
#include "livo/io/log.hpp"
#include "livo/io/run_outputs.hpp"
#include "livo/map/visual_point.hpp"
#include "livo/process/estimator_node.hpp"
#include "livo/process/map_export.hpp"
#include "livo/process/scan_colour.hpp"

#include <cstdio>
#include <cstring>
#include <iostream>
#include <map>
#include <string>

using namespace livo;

namespace {

struct Args {
  std::string log, config, out;
  std::string visual_mode = "adaptive";
  std::string map_mode = "hybrid";
  bool quiet = false;
  bool no_maps = false;  ///< skip map.pcd / map.bt (benchmarks: only the odometry's cost)
  long max_frames = -1;
};

void usage(std::ostream& os) {
  os << "usage: livo-run LOG.lcm --config CFG.yaml --out DIR [--visual-mode adaptive|all|off]\n"
        "                [--map-mode hybrid|global] [--max-frames N] [--no-maps] [--quiet]\n"
        "Runs the odometry on an LCM log in one process and writes trajectory.tum, frames.csv and\n"
        "stats.json into DIR, and map.pcd / map.bt unless --no-maps (their point store and ray casting\n"
        "cost time and memory of their own: benchmarks of the odometry use --no-maps).\n";
}

bool parseArgs(int argc, char** argv, Args& a) {
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&](std::string& dst) {
      if (i + 1 >= argc) throw std::runtime_error(s + " needs a value");
      dst = argv[++i];
    };
    if (s == "--help" || s == "-h") {
      usage(std::cout);
      std::exit(0);
    } else if (s == "--config") value(a.config);
    else if (s == "--out") value(a.out);
    else if (s == "--visual-mode") value(a.visual_mode);
    else if (s == "--map-mode") value(a.map_mode);
    else if (s == "--quiet") a.quiet = true;
    else if (s == "--no-maps") a.no_maps = true;
    else if (s == "--max-frames") {
      std::string v;
      value(v);
      a.max_frames = std::stol(v);
    } else if (!s.empty() && s[0] == '-') throw std::runtime_error("unknown option " + s);
    else if (a.log.empty()) a.log = s;
    else throw std::runtime_error("unexpected argument " + s);
  }
  if (a.log.empty() || a.config.empty() || a.out.empty()) throw std::runtime_error("LOG, --config and --out are required");
  if (a.visual_mode != "adaptive" && a.visual_mode != "all" && a.visual_mode != "off")
    throw std::runtime_error("--visual-mode must be adaptive, all or off (got '" + a.visual_mode + "')");
  if (a.map_mode != "hybrid" && a.map_mode != "global")
    throw std::runtime_error("--map-mode must be hybrid or global (got '" + a.map_mode + "')");
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    parseArgs(argc, argv, args);
  } catch (const std::exception& e) {
    std::cerr << "livo-run: " << e.what() << "\n";
    usage(std::cerr);
    return 2;
  }

  // 1. Configuration: every module reads its sections; unknown keys are errors.
  PipelineConfig pipe_cfg;
  ChannelConfig channels;
  MapExportConfig export_cfg;
  MessageLimits limits;
  try {
    ConfigFile file = ConfigFile::load(args.config);
    const ConfigNode root = file.root();
    pipe_cfg.load(root);
    channels.load(root.section("channels"));
    export_cfg.load(root.section("exporter"));
    EstimatorNodeConfig{}.load(root.section("estimator"));  // livo-estimator's section: checked, not used here
    file.checkAllKeysUsed();
    pipe_cfg.visual_mode = args.visual_mode;
    pipe_cfg.map_mode = args.map_mode;
  } catch (const std::exception& e) {
    std::cerr << "livo-run: " << e.what() << "\n";
    return 2;
  }

  try {
    LogReader reader(args.log);
    RunOutputs outputs(args.out);
    Pipeline pipeline(pipe_cfg);
    std::map<std::string, double> counters;
    Stopwatch wall;
    double last_progress = -1.0;
    bool announced_init = false;
    std::string log_error;

    bool stop = false;
    // map.pcd (camera gray where an image saw the point) and map.bt (OctoMap from the scan rays).
    MapCloud cloud(export_cfg);
    OccupancyMap occupancy(export_cfg);
    const auto addToMaps = [&](const Frame& frame, const FrameResult& r) {
      const Pose T_world_imu = r.lio.state.pose();
      const RegisteredScan scan = colourScan(frame.utime, T_world_imu, r.lio.points, pipeline.camera(),
                                             frame.has_image ? &frame.image : nullptr, pipe_cfg.camera.T_imu_camera,
                                             pipe_cfg.camera.scale);
      const std::vector<Eigen::Vector3f>& pts = scan.points;
      cloud.add(scan.points, scan.intensity, scan.rgb);
      occupancy.insertScan(T_world_imu * pipe_cfg.lio.T_imu_lidar.translation(), pts);
    };
    // frames.csv map_bytes (0 before initialisation). Hybrid mode with a memory cap: the map's O(1)
    // byte estimate after its update, the value the cap is enforced on (the map recounts exactly every
    // map.recount_interval updates). Without a cap the map never recounts (its estimate would use default
    // bytes per item) and in global mode update() returns at once: an exact count (mapStats(), a walk of
    // every structure, its time proportional to the map: ~20 ms for the street scenario's ~60 MB local
    // map) every 10 frames (hybrid) or 50 frames (global), carried forward in between. Not part of the
    // frame timings.
    const bool hybrid = pipeline.map().mode() == MapMode::Hybrid;
    const bool map_estimate_calibrated = hybrid && pipeline.map().config().capBytes() > 0;
    const std::size_t exact_every = hybrid ? 10 : 50;
    std::size_t frames_since_count = exact_every;
    std::uint64_t counted_map_bytes = 0;
    const auto mapBytes = [&](const FrameResult& r) -> std::uint64_t {
      if (!r.lio.initialized) return 0;
      if (map_estimate_calibrated) return r.map.bytes;
      if (++frames_since_count >= exact_every) {
        counted_map_bytes = pipeline.mapStats().bytes;
        frames_since_count = 0;
      }
      return counted_map_bytes;
    };
    const auto onFrame = [&](const Frame& frame, const FrameResult& r) {
      if (stop) return;
      if (!args.no_maps && r.lio.initialized && !r.lio.points.empty()) addToMaps(frame, r);
      FrameRecord rec;
      rec.utime = frame.utime;
      rec.has_pose = r.lio.initialized;
      rec.T_world_imu = r.lio.state.pose();
      rec.lio_ms = r.lio.lio_ms;
      rec.vio_ms = r.vio_ms;
      rec.map_ms = r.lio.map_ms + r.map.ms;  // insertion + slides / evictions
      rec.total_ms = r.total_ms;
      rec.sigma_min = r.lio.sigma_min;
      rec.degenerate = r.degenerate;
      rec.visual_used = r.visual_used;
      rec.n_points = r.lio.n_points;
      rec.n_planes_matched = r.lio.n_matched;
      rec.n_visual_points = r.n_visual_points;
      rec.map_bytes = mapBytes(r);
      outputs.addFrame(rec);
      if (r.lio.initialized && !announced_init && !args.quiet) {
        std::cerr << "livo-run: " << pipeline.odometry().initMessage() << "\n";
        announced_init = true;
      }
      if (r.lio.initialized && r.lio.n_points > 0 && !r.lio.lio_ok && !r.lio.map_started) counters["lio_failed_frames"] += 1;
      if (args.max_frames >= 0 && static_cast<long>(outputs.frames()) >= args.max_frames) stop = true;
    };
    auto runFrames = [&]() { pipeline.processReady(onFrame); };

    // 2. Replay: decode and validate each event, feed the frame builder, run every complete frame.
    LogEvent ev;
    try {
      while (reader.next(ev)) {
        if (ev.channel == channels.imu) {
          livo::imu_t m;
          ImuSample s;
          Validation v = decode(ev.data.data(), ev.data.size(), m, limits);
          if (v) v = fromMsg(m, s);
          if (!v) { counters["rejected_imu"] += 1; continue; }
          pipeline.addImu(s);
        } else if (ev.channel == channels.lidar) {
          livo::lidar_scan_t m;
          LidarScan s;
          std::size_t nonfinite = 0;
          Validation v = decode(ev.data.data(), ev.data.size(), m, limits);
          if (v) v = fromMsg(m, s, limits, &nonfinite);
          if (!v) {
            counters["rejected_scans"] += 1;
            if (!args.quiet) std::cerr << "livo-run: dropped a scan: " << v.error << "\n";
            continue;
          }
          counters["nonfinite_points"] += double(nonfinite);
          pipeline.addScan(s);
        } else if (ev.channel == channels.camera) {
          if (!pipe_cfg.preprocess.camera_enabled) continue;
          livo::image_t m;
          Image img, gray;
          std::string err;
          Validation v = decode(ev.data.data(), ev.data.size(), m, limits);
          if (v) v = fromMsg(m, img, limits);
          if (v && !toGray8(img, gray, &err)) v = Validation::fail(err);
          if (!v) {
            counters["rejected_images"] += 1;
            if (!args.quiet) std::cerr << "livo-run: dropped an image: " << v.error << "\n";
            continue;
          }
          pipeline.addImage(gray);
        } else {
          continue;
        }
        runFrames();
        if (stop) break;
        const double secs = wall.elapsedMs() / 1000.0;
        if (!args.quiet && secs - last_progress > 0.5) {
          last_progress = secs;
          std::fprintf(stderr, "\rlivo-run: %5.1f%% of log, %zu frames, %.1f frames/s   ",
                       100.0 * double(reader.position()) / double(std::max<std::uint64_t>(1, reader.fileSize())),
                       outputs.frames(), double(outputs.frames()) / std::max(1e-3, secs));
        }
      }
      if (!stop) {
        pipeline.flush();
        runFrames();
      }
    } catch (const LogError& e) {
      log_error = e.what();  // keep everything processed so far; report below
    }
    if (!args.quiet) std::fprintf(stderr, "\n");

    // 3. Outputs: stats.json + a summary on stdout.
    const PreprocessStats& pst = pipeline.recombiner().stats();
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
    const HybridMapStats hs = pipeline.mapStats();
    MapSummary ms;
    ms.local_voxels = hs.local_voxels;
    ms.visual_points_local = hs.visual_points_local;
    ms.visual_points_longterm = hs.visual_points_longterm;
    ms.bytes = hs.bytes;
    if (!args.no_maps) {
      cloud.writePcd(args.out + "/map.pcd");
      if (export_cfg.octomap_enabled) occupancy.writeBt(args.out + "/map.bt");
    }
    counters["map_pcd_points"] = double(cloud.size());
    const HybridMapCounters& mc = hs.counters;
    for (const auto& [k, v] : std::map<std::string, double>{
             {"slides", double(mc.slides)}, {"longterm_slides", double(mc.longterm_slides)},
             {"removed_voxels", double(mc.removed_voxels)}, {"moved_to_longterm", double(mc.moved_to_longterm)},
             {"moved_to_local", double(mc.moved_to_local)}, {"deleted_points", double(mc.deleted_points)},
             {"eviction_events", double(mc.eviction_events)}, {"evicted_longterm_points", double(mc.evicted_longterm_points)},
             {"evicted_local_voxels", double(mc.evicted_local_voxels)}, {"evicted_local_points", double(mc.evicted_local_points)},
             {"max_update_ms", mc.max_update_ms}, {"max_slide_ms", mc.max_slide_ms}})
      counters["map_" + k] = v;
    counters["map_bt_scans_dropped"] = double(occupancy.scansDropped());
    counters["images_wrong_size"] = double(pipeline.imagesWrongSize());
    const double rss = bytesToMb(peakRssBytes());
    std::map<std::string, std::string> notes{{"visual_mode", args.visual_mode}, {"map_mode", args.map_mode},
                                             {"log", args.log}, {"config", args.config}};
    if (!log_error.empty()) notes["log_error"] = log_error;
    outputs.writeStats(ms, rss, counters, notes);
    std::cout << outputs.summary(rss);
    if (!args.quiet) std::cout << "preprocessing:\n" << pst.summary() << "\n";
    std::cout << "outputs in " << args.out << "\n";
    if (!log_error.empty()) {
      std::cerr << "livo-run: error: " << log_error << " (outputs up to this point were written)\n";
      return 1;
    }
  } catch (const std::exception& e) {
    std::cerr << "livo-run: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
