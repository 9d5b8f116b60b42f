// livo-estimator --config CFG.yaml [--lcm-url URL] [--idle-exit S] [--visual-mode adaptive|all|off]
//                [--threads N] [--report-interval S] [--print-config]
//
// LIVO_FRAME in; per frame a LIVO_MAP_QUERY to livo-mapserver and its LIVO_SUBMAP back, then
// LIVO_MAP_UPDATE, LIVO_ODOMETRY, LIVO_REGISTERED_SCAN and LIVO_ESTIMATOR_STATS out (libs/process
// EstimatorNode around FramePipeline with RemoteMap). Reads the rig sections the pipeline uses, `estimator` and
// `channels`. Exits on SIGINT / SIGTERM (or --idle-exit) after the queued frames, with a summary.
#include "livo/common/config.hpp"
#include "livo/io/channels.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/estimator_node.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/stop_signal.hpp"

#include <cstring>
#include <iostream>

using namespace livo;

int main(int argc, char** argv) {
  installStopHandlers();
  CommandLine cl("livo-estimator",
                 "Runs the odometry on LIVO_FRAME messages with the map in livo-mapserver (LIVO_MAP_QUERY /\n"
                 "LIVO_SUBMAP / LIVO_MAP_UPDATE) and publishes LIVO_ODOMETRY, LIVO_REGISTERED_SCAN and\n"
                 "LIVO_ESTIMATOR_STATS. Stops on SIGINT / SIGTERM with a summary.");
  ProcessArgs args;
  std::string visual_mode = "adaptive";
  double report_interval_s = 5.0;
  int threads = defaultThreadCount();
  addProcessOptions(cl, args);
  cl.choice("--visual-mode", &visual_mode, {"adaptive", "all", "off"},
            "adaptive: keyframes, every frame while LiDAR is degenerate; all: every image; off: LiDAR-inertial");
  addThreadsOption(cl, &threads);
  cl.number("--report-interval", &report_interval_s, "S", "progress on stderr every S s of message time (0: off)", 0.0)
      .unit("s");
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;

  PipelineConfig pipe_cfg;
  EstimatorNodeConfig node_cfg;
  ChannelConfig channels;
  try {
    ConfigFile file = ConfigFile::load(args.config);
    const ConfigNode root = file.root();
    pipe_cfg.load(root);
    node_cfg.load(root.section("estimator"));
    channels.load(root.section("channels"));
    checkSectionsUsed(file, {"channels", "estimator", "lio", "vio", "selector"});
    node_cfg.config_lines = file.effectiveLines();
    pipe_cfg.visual_mode = parseVisualMode(visual_mode);  // command-line settings: PipelineConfig has no keys for them
    pipe_cfg.threads = threads;
    if (args.print_config) {
      printConfig(std::cout, cl.program(), file, "--visual-mode " + visual_mode);
      return kExitOk;
    }
  } catch (const std::exception& e) {
    std::cerr << "livo-estimator: " << e.what() << "\n";
    return kExitUsage;
  }

  try {
    const std::string url = resolveLcmUrl(args.lcm_url);
    LcmNode lcm(url, "livo-estimator", &std::cerr);
    EstimatorNode node(lcm, pipe_cfg, node_cfg, channels, &std::cerr);
    std::cerr << "livo-estimator: " << channels.frame << " -> " << channels.odometry << " (map via "
              << channels.map_query << " / " << channels.submap << ", visual mode " << visual_mode << ") on " << url
              << "\n";
    Utime last_report = 0;
    const auto poll = [&]() {
      if (node.poll() == 0) return;
      const Utime t = node.counters().last_utime;
      if (report_interval_s > 0 && toSeconds(t - last_report) >= report_interval_s) {
        std::cerr << "livo-estimator: " << node.progressLine() << "\n";
        last_report = t;
      }
    };
    const LcmNode::SpinEnd end = lcm.spin(args.idle_exit_s, poll);
    // Drain on stop: the messages already received (in the socket) are handled, then every queued
    // frame is processed and published before the exit.
    lcm.drainOnStop();
    node.poll();
    std::cerr << "livo-estimator: "
              << (end == LcmNode::SpinEnd::kIdle ? "no message for --idle-exit seconds"
                                                 : stopSignal() ? strsignal(stopSignal()) : "stop requested")
              << ", stopping\nlivo-estimator: " << node.progressLine() << "\n";
    std::cout << node.summary();
  } catch (const std::exception& e) {
    std::cerr << "livo-estimator: error: " << e.what() << "\n";
    return kExitRunError;
  }
  return kExitOk;
}
