// livo-mapserver --config CFG.yaml [--lcm-url URL] [--idle-exit S] [--map-mode hybrid|global]
//                [--memory-cap-mb N] [--map-file FILE] [--prior-map DIR] [--report-interval S] [--print-config]
//
// Owns the map (local voxel plane map + visual maps; hybrid: sliding local cube and long-term visual
// map, memory cap): answers LIVO_MAP_QUERY with LIVO_SUBMAP, applies LIVO_MAP_UPDATE, publishes
// LIVO_MAP_STATS once per second of message time. With --map-file, loads FILE at start when it exists
// and saves the map there on SIGINT / SIGTERM / --idle-exit, so a restarted server continues with it.
#include "livo/common/config.hpp"
#include "livo/estimation/pipeline.hpp"
#include "livo/io/channels.hpp"
#include "livo/loop/prior_seeder.hpp"
#include "livo/loop/site_map.hpp"
#include "livo/map/map_file.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/mapserver_node.hpp"
#include "livo/process/stop_signal.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <optional>

using namespace livo;

int main(int argc, char** argv) {
  installStopHandlers();
  CommandLine cl("livo-mapserver",
                 "Serves the map to livo-estimator (LIVO_MAP_QUERY -> LIVO_SUBMAP, LIVO_MAP_UPDATE) and publishes\n"
                 "LIVO_MAP_STATS at 1 Hz. Stops on SIGINT / SIGTERM with a summary (saving --map-file).");
  ProcessArgs args;
  std::string map_mode = "hybrid";
  std::string map_file, prior_map;
  double cap_mb = -1.0;
  double report_interval_s = 10.0;
  addProcessOptions(cl, args);
  cl.choice("--map-mode", &map_mode, {"hybrid", "global"},
            "hybrid: sliding local map + long-term visual map; global: one unbounded map (FAST-LIVO2)");
  cl.number("--memory-cap-mb", &cap_mb, "N", "memory cap of the map (0: none; overrides map.memory_cap_mb)", 0.0)
      .unit("MiB")
      .defaultText("config map.memory_cap_mb");
  cl.text("--prior-map", &prior_map, "DIR",
          "serve the planes of the site map DIR near the robot once livo-loop --prior-map DIR localised the odometry "
          "in it (LIVO_MAP_CORRECTION)");
  cl.text("--map-file", &map_file, "FILE", "load the map from FILE at start (when it exists), save it there at exit");
  cl.number("--report-interval", &report_interval_s, "S", "progress on stderr every S s of message time (0: off)", 0.0)
      .unit("s");
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;

  PipelineConfig pipe_cfg;
  LoopConfig loop_cfg;
  ChannelConfig channels;
  std::string config_lines;
  try {
    ConfigFile file = ConfigFile::load(args.config);
    const ConfigNode root = file.root();
    pipe_cfg.load(root);
    channels.load(root.section("channels"));
    checkSectionsUsed(file, {"channels", "map", "voxel_map"});
    loop_cfg.load(root.section("loop"), pipe_cfg.preprocess.max_range_m, pipe_cfg.lio.lio.range_noise_m,
                  pipe_cfg.lio.lio.beam_noise_deg);
    config_lines = file.effectiveLines();
    if (args.print_config) {
      if (cap_mb >= 0) file.overrideEffective("map.memory_cap_mb", cap_mb);
      printConfig(std::cout, cl.program(), file, "--map-mode " + map_mode);
      return kExitOk;
    }
  } catch (const std::exception& e) {
    std::cerr << "livo-mapserver: " << e.what() << "\n";
    return kExitUsage;
  }

  try {
    HybridMapConfig map_cfg = pipe_cfg.map;
    map_cfg.mode = parseMapMode(map_mode);
    MapService service(map_cfg, pipe_cfg.lio.map, pipe_cfg.visual_map);
    if (cap_mb >= 0) service.map().setMemoryCapMb(cap_mb);
    if (!map_file.empty() && std::filesystem::exists(map_file)) {
      const MapFileInfo info = loadMap(map_file, service.map());
      std::cerr << "livo-mapserver: loaded " << map_file << ": " << info.describe() << "\n";
    }
    const std::string url = resolveLcmUrl(args.lcm_url);
    LcmNode lcm(url, "livo-mapserver", &std::cerr);
    // IMU samples kept after the estimator's last filter state, for a restarted estimator: 30 s at
    // imu.rate_hz (within the message limit of a resume answer).
    const auto max_resume_imu = std::size_t(std::clamp(30.0 * pipe_cfg.lio.imu.rate_hz, 100.0,
                                                        double(lcm.limits().max_imu_per_frame)));
    MapServerNode node(lcm, service, channels, &std::cerr, 1.0, max_resume_imu);
    node.setConfigLines(config_lines);
    std::optional<SiteMap> site;
    std::optional<PriorMapSeeder> seeder;
    if (!prior_map.empty()) {
      site.emplace(prior_map, loop_cfg.site_budget_mb, loop_cfg.descriptor);
      seeder.emplace(*site, loop_cfg);
      node.setPriorMap(&*seeder);
      std::cerr << "livo-mapserver: site map " << prior_map << " (" << site->size()
                << " keyframes): its planes are served once livo-loop --prior-map localises\n";
    }
    std::cerr << "livo-mapserver: " << map_mode << " map";
    if (service.map().stats().cap_bytes > 0) std::cerr << ", cap " << service.map().stats().cap_bytes / (1 << 20) << " MiB";
    std::cerr << "; " << channels.map_query << " -> " << channels.submap << ", " << channels.map_update << " on " << url
              << "\n";
    Utime last_report = 0;
    const auto poll = [&]() {
      const Utime t = service.latestTime();
      if (report_interval_s > 0 && toSeconds(t - last_report) >= report_interval_s) {
        std::cerr << "livo-mapserver: " << node.progressLine() << "\n";
        last_report = t;
      }
    };
    const LcmNode::SpinEnd end = lcm.spin(args.idle_exit_s, poll);
    lcm.drainOnStop();  // drain on stop: updates already received go into the map that is saved
    poll();
    std::cerr << "livo-mapserver: "
              << (end == LcmNode::SpinEnd::kIdle ? "no message for --idle-exit seconds"
                                                 : stopSignal() ? strsignal(stopSignal()) : "stop requested")
              << ", stopping\n";
    node.publishStats();
    if (!map_file.empty()) {
      const MapFileInfo info = saveMap(map_file, service.map());
      std::cerr << "livo-mapserver: saved " << map_file << ": " << info.describe() << "\n";
    }
    std::cout << node.summary();
  } catch (const std::exception& e) {
    std::cerr << "livo-mapserver: error: " << e.what() << "\n";
    return kExitRunError;
  }
  return kExitOk;
}
