// livo-run LOG.lcm --config CFG.yaml --out DIR [--visual-mode adaptive|all|off] [--map-mode hybrid|global]
//          [--threads N] [--max-frames N] [--no-maps] [--loop] [--save-map DIR] [--prior-map DIR]
//          [--progress] [--quiet] [--print-config]
//
// Runs the whole pipeline in one process (no network) on an LCM log, as fast as possible:
// log events -> validated structs -> frame builder (recut sweeps + IMU + image) -> odometry -> outputs.
// Writes DIR/trajectory.tum, DIR/frames.csv (map_bytes: see MapBytes in run_log.cpp), DIR/stats.json (with
// --loop also DIR/trajectory_map.tum, the trajectory in the loop-corrected map frame; with --prior-map
// the same file in the saved site map's frame); a
// progress line on stderr and a summary on stdout. A truncated or corrupt log stops the run with an
// error after writing what was processed.
#include "run_log.hpp"

#include "livo/cli/command_line.hpp"
#include "livo/cli/progress.hpp"
#include "livo/common/config.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/estimator_node.hpp"

#include <iostream>

using namespace livo;

namespace {

void addOptions(CommandLine& cl, livo_run::Args& a) {
  cl.positional("LOG.lcm", &a.log, "LCM log (LIVO_IMU, LIVO_LIDAR, LIVO_CAMERA; channel names from the config)")
      .requiredUnless("--print-config");
  cl.text("--config", &a.config, "CFG.yaml", "rig config (config/README.md)").required();
  cl.text("--out", &a.out, "DIR", "output directory (created; existing files are replaced)")
      .requiredUnless("--print-config");
  cl.choice("--visual-mode", &a.visual_mode, {"adaptive", "all", "off"},
            "adaptive: keyframes, every frame while LiDAR is degenerate; all: every image (FAST-LIVO2); "
            "off: LiDAR-inertial only");
  cl.choice("--map-mode", &a.map_mode, {"hybrid", "global"},
            "hybrid: sliding local map + long-term visual map; global: one unbounded map (FAST-LIVO2)");
  addThreadsOption(cl, &a.threads);
  cl.count("--max-frames", &a.max_frames, "N", "stop after N frames").defaultText("all");
  cl.flag("--no-maps", &a.no_maps,
          "skip map.pcd / map.bt (their point store and ray casting cost time and memory of their own: "
          "benchmarks of the odometry use --no-maps)");
  cl.flag("--loop", &a.loop,
          "loop closure: keyframes, place recognition, verified loops and a pose graph (config section `loop`); "
          "writes trajectory_map.tum, the trajectory in the corrected map frame, and loop_* counters");
  cl.text("--save-map", &a.save_map, "DIR",
          "at the end, write the loop closer's keyframes (map-frame poses, place descriptors, points in tiles) as a "
          "site map into DIR, to localise in later with --prior-map; implies --loop");
  cl.text("--prior-map", &a.prior_map, "DIR",
          "localise in the site map DIR (no initial pose needed): trajectory_map.tum holds the frames from the "
          "first relocalised one on, in the map's frame; reloc_* counters in stats.json");
  addProgressOption(cl, &a.progress);
  cl.flag("--quiet", &a.quiet, "no progress line and no preprocessing summary");
  cl.flag("--print-config", &a.print_config, kPrintConfigHelp);
}

/// Every module reads its sections of the config; unknown keys are errors (ConfigError).
ConfigFile loadConfig(const livo_run::Args& args, livo_run::Config& cfg) {
  ConfigFile file = ConfigFile::load(args.config);
  const ConfigNode root = file.root();
  cfg.pipe.load(root);
  // The loop section takes the LiDAR's range and noise from the configs that read them.
  cfg.loop.load(root.section("loop"), cfg.pipe.preprocess.max_range_m, cfg.pipe.lio.lio.range_noise_m,
                cfg.pipe.lio.lio.beam_noise_deg);
  cfg.channels.load(root.section("channels"));
  cfg.exporter.load(root.section("exporter"));
  EstimatorNodeConfig{}.load(root.section("estimator"));  // livo-estimator's section: checked, not used here
  file.checkAllKeysUsed();
  cfg.pipe.visual_mode = parseVisualMode(args.visual_mode);  // command-line settings: PipelineConfig has no keys for them
  cfg.pipe.map_mode = parseMapMode(args.map_mode);
  cfg.pipe.threads = args.threads;
  return file;
}

}  // namespace

int main(int argc, char** argv) {
  // 1. Command line.
  livo_run::Args args;
  CommandLine cl("livo-run",
                 "Runs the odometry on an LCM log in one process and writes trajectory.tum, frames.csv and\n"
                 "stats.json into DIR, and map.pcd / map.bt unless --no-maps.");
  addOptions(cl, args);
  cl.epilog("Besides the exit statuses below: " + std::to_string(kExitLostSpans) +
            " when the run finished and wrote every output but its estimate was lost for a span (frames.csv "
            "state 'lost'; stats.json health.lost_spans).");
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;
  if (!args.save_map.empty()) args.loop = true;
  if (args.loop && !args.prior_map.empty()) {
    std::cerr << "livo-run: --prior-map with --loop / --save-map is not supported yet (localise in one map, or make one)\n"
              << "try 'livo-run --help'\n";
    return kExitUsage;
  }

  // 2. Configuration (or, with --print-config, only its effective values).
  livo_run::Config cfg;
  try {
    const ConfigFile file = loadConfig(args, cfg);
    if (args.print_config) {
      printConfig(std::cout, cl.program(), file, "--visual-mode " + args.visual_mode + " --map-mode " + args.map_mode);
      return kExitOk;
    }
  } catch (const std::exception& e) {
    std::cerr << "livo-run: " << e.what() << "\n";
    return kExitUsage;
  }

  // 3. The run: replay, per-frame outputs, stats and summary.
  try {
    return livo_run::runLog(args, cfg);
  } catch (const std::exception& e) {
    std::cerr << "livo-run: error: " << e.what() << "\n";
    return kExitRunError;
  }
}
