// livo-preprocess --config CFG.yaml [--lcm-url URL] [--idle-exit S] [--report-interval S] [--print-config]
//
// Raw sensor messages (LIVO_IMU, LIVO_LIDAR, LIVO_CAMERA) in, estimator frames (LIVO_FRAME) out:
// the LiDAR stream recut at the image times with the IMU samples covering each sweep and the gray
// image (libs/process PreprocessNode around the sensors' Recombiner). Reads the config sections
// lidar / imu / camera (time offsets, filters), preprocess and channels. Exits on SIGINT / SIGTERM
// (or --idle-exit) after publishing what the recombiner still holds, with a summary on stdout.
#include "livo/common/config.hpp"
#include "livo/io/channels.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/preprocess_node.hpp"
#include "livo/process/stop_signal.hpp"

#include <csignal>
#include <cstring>
#include <iostream>

using namespace livo;

int main(int argc, char** argv) {
  installStopHandlers();
  CommandLine cl("livo-preprocess",
                 "Recuts raw LIVO_IMU / LIVO_LIDAR / LIVO_CAMERA into LIVO_FRAME messages (channel names from\n"
                 "the config's `channels` section). Stops on SIGINT / SIGTERM with a summary.");
  ProcessArgs args;
  double report_interval_s = 5.0;
  addProcessOptions(cl, args);
  cl.number("--report-interval", &report_interval_s, "S", "counters on stderr every S s of message time (0: off)", 0.0)
      .unit("s");
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;

  PreprocessConfig cfg;
  ChannelConfig channels;
  try {
    ConfigFile file = ConfigFile::load(args.config);
    const ConfigNode root = file.root();
    cfg.load(root);
    channels.load(root.section("channels"));
    checkSectionsUsed(file, {"channels", "preprocess"});
    if (args.print_config) {
      printConfig(std::cout, cl.program(), file);
      return kExitOk;
    }
  } catch (const std::exception& e) {
    std::cerr << "livo-preprocess: " << e.what() << "\n";
    return kExitUsage;
  }

  try {
    const std::string url = resolveLcmUrl(args.lcm_url);
    LcmNode lcm(url, "livo-preprocess", &std::cerr);
    PreprocessNode node(lcm, cfg, channels, &std::cerr, report_interval_s);
    std::cerr << "livo-preprocess: " << channels.imu << " + " << channels.lidar << " + " << channels.camera
              << (cfg.camera_enabled ? "" : " (camera disabled)") << " -> " << channels.frame << " on " << url
              << "\n";
    const LcmNode::SpinEnd end = lcm.spin(args.idle_exit_s);
    lcm.drainOnStop();    // drain on stop: the messages already received are handled,
    node.finish();  // and the frames they complete are published
    std::cerr << "livo-preprocess: "
              << (end == LcmNode::SpinEnd::kIdle ? "no message for --idle-exit seconds"
                                                 : stopSignal() ? strsignal(stopSignal()) : "stop requested")
              << ", stopping\nlivo-preprocess: " << node.progressLine() << "\n";
    std::cout << node.summary();
  } catch (const std::exception& e) {
    std::cerr << "livo-preprocess: error: " << e.what() << "\n";
    return kExitRunError;
  }
  return kExitOk;
}
