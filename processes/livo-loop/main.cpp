// livo-loop --config CFG.yaml [--lcm-url URL] [--idle-exit S] [--memory-cap-mb N] [--save-map DIR]
//           [--prior-map DIR] [--report-interval S] [--print-config]
//
// Loop closure beside the odometry (LoopNode, libs/loop): keyframes from LIVO_ODOMETRY and
// LIVO_REGISTERED_SCAN, place recognition, verified loops and a pose graph; publishes the map frame on
// LIVO_MAP_CORRECTION after every keyframe and, on SIGINT / SIGTERM / --idle-exit, after its last solve.
// Reads the config sections channels and loop (and the LiDAR's max_range_m, range_noise_m and
// beam_noise_deg). --memory-cap-mb bounds the keyframe points held in memory (loop.points_budget_mb);
// older keyframes' points go to a spill file in loop.spill_dir. --save-map writes the keyframes as a site
// map at exit; --prior-map localises in one instead of closing loops (relocaliser.hpp).
#include "livo/common/config.hpp"
#include "livo/common/timing.hpp"
#include "livo/estimation/pipeline.hpp"
#include "livo/io/channels.hpp"
#include "livo/loop/site_map.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/loop_node.hpp"
#include "livo/process/stop_signal.hpp"

#include <cstring>
#include <iostream>
#include <optional>

using namespace livo;

int main(int argc, char** argv) {
  installStopHandlers();
  CommandLine cl("livo-loop",
                 "Loop closure: keyframes from LIVO_ODOMETRY + LIVO_REGISTERED_SCAN, verified loops, a pose graph;\n"
                 "publishes the map frame on LIVO_MAP_CORRECTION. Stops on SIGINT / SIGTERM with a final solve.");
  ProcessArgs args;
  double cap_mb = -1.0;
  double report_interval_s = 30.0;
  std::string save_map, prior_map;
  addProcessOptions(cl, args);
  cl.number("--memory-cap-mb", &cap_mb, "N",
            "keyframe points held in memory (0: no budget; older ones spill to disk; overrides loop.points_budget_mb)",
            0.0)
      .unit("MiB")
      .defaultText("config loop.points_budget_mb");
  cl.text("--save-map", &save_map, "DIR",
          "at exit, after the last solve, write the keyframes as a site map into DIR (livo-run --prior-map DIR "
          "localises in it)");
  cl.text("--prior-map", &prior_map, "DIR",
          "localise in the site map DIR instead of closing loops (no initial pose needed): the corrections carry "
          "the anchors, and livo-exporter's trajectory_map.tum is in the map's frame");
  cl.number("--report-interval", &report_interval_s, "S", "progress on stderr every S s of message time (0: off)", 0.0)
      .unit("s");
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;
  if (!save_map.empty() && !prior_map.empty()) {
    std::cerr << "livo-loop: --save-map and --prior-map together are not supported yet\ntry 'livo-loop --help'\n";
    return kExitUsage;
  }

  LoopConfig cfg;
  ChannelConfig channels;
  try {
    ConfigFile file = ConfigFile::load(args.config);
    const ConfigNode root = file.root();
    PipelineConfig pipe;
    pipe.load(root);
    cfg.load(root.section("loop"), pipe.preprocess.max_range_m, pipe.lio.lio.range_noise_m, pipe.lio.lio.beam_noise_deg);
    channels.load(root.section("channels"));
    checkSectionsUsed(file, {"channels", "loop"});
    if (cap_mb >= 0) cfg.points_budget_mb = cap_mb;
    if (args.print_config) {
      if (cap_mb >= 0) file.overrideEffective("loop.points_budget_mb", cap_mb);
      printConfig(std::cout, cl.program(), file);
      return kExitOk;
    }
  } catch (const std::exception& e) {
    std::cerr << "livo-loop: " << e.what() << "\n";
    return kExitUsage;
  }

  try {
    const std::string url = resolveLcmUrl(args.lcm_url);
    LcmNode lcm(url, "livo-loop", &std::cerr);
    std::optional<SiteMap> site;
    if (!prior_map.empty()) site.emplace(prior_map, cfg.site_budget_mb, cfg.descriptor);
    LoopNode node(lcm, channels, cfg, &std::cerr, site ? &*site : nullptr);
    if (site) {
      std::cerr << "livo-loop: localising in the site map " << prior_map << " (" << site->size() << " keyframes)";
    } else {
      std::cerr << "livo-loop: keyframe points budget ";
      if (cfg.points_budget_mb > 0) std::cerr << cfg.points_budget_mb << " MiB";
      else std::cerr << "none";
    }
    std::cerr << "; " << channels.odometry << " + " << channels.registered_scan << " -> " << channels.map_correction
              << " on " << url << "\n";
    double last_report_s = 0.0;
    const auto poll = [&]() {
      const double t = toSeconds(node.lastFrameTime());
      if (report_interval_s > 0 && t - last_report_s >= report_interval_s) {
        std::cerr << "livo-loop: " << node.progressLine() << "\n";
        last_report_s = t;
      }
    };
    const LcmNode::SpinEnd end = lcm.spin(args.idle_exit_s, poll);
    lcm.drainOnStop();
    std::cerr << "livo-loop: "
              << (end == LcmNode::SpinEnd::kIdle ? "no message for --idle-exit seconds"
                                                 : stopSignal() ? strsignal(stopSignal()) : "stop requested")
              << (site ? ", final correction\n" : ", final solve and correction\n");
    node.finish();
    if (!save_map.empty()) {
      saveSiteMap(save_map, *node.closer(), cfg.descriptor, cfg.site_tile_m);
      std::cerr << "livo-loop: site map of " << node.closer()->graph().size() << " keyframes in " << save_map << "\n";
    }
    std::cout << node.summary() << "peak RSS " << bytesToMb(peakRssBytes()) << " MB\n";
  } catch (const std::exception& e) {
    std::cerr << "livo-loop: error: " << e.what() << "\n";
    return kExitRunError;
  }
  return kExitOk;
}
