// livo-exporter --config CFG.yaml --out DIR [--lcm-url URL] [--idle-exit S] [--print-config]
//
// Writes the output directory of a multi-process run, in livo-run's formats: trajectory.tum and
// frames.csv as the frames arrive (flushed per line), and on SIGINT / SIGTERM (or --idle-exit)
// stats.json, map.pcd (PCL, coloured where a camera saw the point) and map.bt (OctoMap). Reads the
// config sections channels and exporter (map_voxel_m, octomap_resolution_m, ...: map_export.hpp).
#include "livo/common/config.hpp"
#include "livo/io/channels.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/exporter_node.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/stop_signal.hpp"

#include <cstring>
#include <iostream>

using namespace livo;

int main(int argc, char** argv) {
  installStopHandlers();
  CommandLine cl("livo-exporter",
                 "Writes trajectory.tum, frames.csv, stats.json, map.pcd and map.bt into DIR from LIVO_ODOMETRY,\n"
                 "LIVO_ESTIMATOR_STATS, LIVO_REGISTERED_SCAN and LIVO_MAP_STATS. Stops on SIGINT / SIGTERM.");
  ProcessArgs args;
  std::string out;
  addProcessOptions(cl, args);
  cl.text("--out", &out, "DIR", "output directory (created; existing files are replaced)")
      .requiredUnless("--print-config");
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;

  MapExportConfig cfg;
  ChannelConfig channels;
  try {
    ConfigFile file = ConfigFile::load(args.config);
    const ConfigNode root = file.root();
    cfg.load(root.section("exporter"));
    channels.load(root.section("channels"));
    checkSectionsUsed(file, {"channels", "exporter"});
    if (args.print_config) {
      printConfig(std::cout, cl.program(), file);
      return kExitOk;
    }
  } catch (const std::exception& e) {
    std::cerr << "livo-exporter: " << e.what() << "\n";
    return kExitUsage;
  }

  try {
    const std::string url = resolveLcmUrl(args.lcm_url);
    LcmNode lcm(url, "livo-exporter", &std::cerr);
    ExporterNode node(lcm, channels, cfg, out, &std::cerr);
    std::cerr << "livo-exporter: " << channels.odometry << " + " << channels.estimator_stats << " + "
              << channels.registered_scan << " + " << channels.map_stats << " on " << url << " -> " << out << "\n";
    const LcmNode::SpinEnd end = lcm.spin(args.idle_exit_s);
    lcm.drainOnStop();  // drain on stop: the messages already received are written too
    std::cerr << "livo-exporter: "
              << (end == LcmNode::SpinEnd::kIdle ? "no message for --idle-exit seconds"
                                                 : stopSignal() ? strsignal(stopSignal()) : "stop requested")
              << ", writing stats.json, map.pcd, map.bt\n";
    node.finish();
    std::cout << node.summary();
  } catch (const std::exception& e) {
    std::cerr << "livo-exporter: error: " << e.what() << "\n";
    return kExitRunError;
  }
  return kExitOk;
}
