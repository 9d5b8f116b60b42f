// livo-run's run: the log replayed through one Pipeline, the outputs written (main.cpp: command line and
// configuration).
#pragma once

#include "livo/common/worker_pool.hpp"
#include "livo/estimation/pipeline.hpp"
#include "livo/io/channels.hpp"
#include "livo/loop/loop_closer.hpp"
#include "livo/process/map_export.hpp"

#include <cstdint>
#include <string>

namespace livo_run {

/// The command line (main.cpp registers it).
struct Args {
  std::string log, config, out;
  std::string visual_mode = "adaptive";
  std::string map_mode = "hybrid";
  int threads = livo::defaultThreadCount();  ///< threads of the per-frame loops (same results for every count)
  bool quiet = false;
  bool progress = false;  ///< the progress line also when stderr is not a terminal
  bool no_maps = false;  ///< skip map.pcd / map.bt (benchmarks: only the odometry's cost)
  bool loop = false;     ///< loop closure (libs/loop): trajectory_map.tum and the loop counters
  std::string save_map;  ///< with loop closure: the site map written here at the end (site_map.hpp)
  std::string prior_map; ///< localise in this site map: trajectory_map.tum in its frame (relocaliser.hpp)
  std::int64_t max_frames = -1;
  bool print_config = false;
};

/// Everything the run reads from the config file (plus the command-line modes in `pipe`).
struct Config {
  livo::PipelineConfig pipe;
  livo::ChannelConfig channels;
  livo::MapExportConfig exporter;
  livo::LoopConfig loop;  ///< section `loop` (read and checked always, used with --loop)
};

/// Replays args.log through the pipeline and writes args.out (trajectory.tum, frames.csv, stats.json,
/// map.pcd, map.bt; with --loop trajectory_map.tum), a progress line on stderr and a summary on stdout. Returns kExitOk, or kExitRunError
/// after writing what was processed when the log is truncated or corrupt; throws on other run-time
/// errors (missing log, unwritable output directory).
int runLog(const Args& args, const Config& cfg);

}  // namespace livo_run
