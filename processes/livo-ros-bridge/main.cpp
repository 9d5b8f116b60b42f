// livo-ros-bridge --config CFG.yaml [--lidar-topic T] [--imu-topic T] [--image-topic T] [--world-frame F]
//                 [--body-frame F] [--stats S] [--lcm-url URL] [--print-config] ...
//
// ROS 1 sensor drivers -> the suite, and the suite -> RViz:
//   ROS -> LCM: sensor_msgs/Imu, PointCloud2, livox_ros_driver(2)/CustomMsg, Image, CompressedImage through
//     the decoders and rules of `livo-convert rosbag` (libs/datasets ros_input.hpp: topic auto-detection,
//     utime rules, IMU in g) to LIVO_IMU, LIVO_LIDAR, LIVO_CAMERA (sensor_input.hpp);
//   LCM -> ROS: odometry, tf, registered scan, decimated map, diagnostics (estimator_outputs.hpp).
// Never fatal after start-up: a missing ROS master is waited for, one that restarts is registered with
// again, bad topics and messages are counted and warned about at a limited rate (ros_session.hpp).
// SIGINT / SIGTERM stop it cleanly; the summary (counts, drops, added latency, CPU) goes to stdout.
#include "bridge_log.hpp"
#include "bridge_options.hpp"
#include "estimator_outputs.hpp"
#include "report.hpp"
#include "ros_session.hpp"
#include "sensor_input.hpp"

#include "livo/common/config.hpp"
#include "livo/datasets/ros_cli.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/stop_signal.hpp"

#include <ros/master.h>
#include <ros/names.h>
#include <ros/ros.h>

#include <cstring>
#include <iostream>

using namespace livo;
using namespace livo_bridge;

namespace {

void addBridgeOptions(CommandLine& cl, BridgeOptions& o) {
  cl.text("--world-frame", &o.world_frame, "F", "frame of the odometry, the scans and the map (tf parent)");
  cl.text("--body-frame", &o.body_frame, "F", "frame of the IMU (tf child, odometry child_frame_id)");
  cl.text("--topic-prefix", &o.topic_prefix, "P", "prefix of the published topics P/odometry, P/registered_scan, P/map");
  cl.text("--node-name", &o.node_name, "NAME", "ROS node name");
  cl.text("--ros-master", &o.ros_master, "URI", "ROS master").defaultText("$ROS_MASTER_URI, else http://localhost:11311");
  cl.integer("--queue", &o.queue, "N",
             "messages queued per LiDAR / camera topic (roscpp) and per LCM output channel; when full the oldest "
             "is dropped and counted",
             1, 100000);
  cl.integer("--imu-queue", &o.imu_queue, "N", "messages queued per IMU topic", 1, 1000000);
  cl.number("--map-voxel", &o.map_voxel_m, "M", "voxel of the decimated map (one point each)", 0.0, true).unit("m");
  cl.integer("--map-max-points", &o.map_max_points, "N", "map points kept; above, the map voxel doubles", 1,
             100'000'000);
  cl.number("--map-period", &o.map_period_s, "S", "message time between two map messages", 0.0, true).unit("s");
  cl.number("--stats", &o.stats_s, "S",
            "print counts, drops, added latency (median, p99) and CPU use every S seconds on stderr (0: only the "
            "summary at exit)",
            0.0)
      .unit("s");
}

/// Topic names as the master lists them (a relative name resolves in the node's namespace).
void resolveTopics(RosInputOptions& in) {
  for (std::string* t : {&in.lidar_topic, &in.imu_topic, &in.image_topic})
    if (!t->empty() && *t != "none") *t = ros::names::resolve(*t);
}

}  // namespace

int main(int argc, char** argv) {
  installStopHandlers();
  CommandLine cl("livo-ros-bridge",
                 "Bridges ROS 1 sensor drivers to the suite (sensor_msgs/Imu, PointCloud2, livox_ros_driver(2)/CustomMsg,\n"
                 "Image, CompressedImage -> LIVO_IMU, LIVO_LIDAR, LIVO_CAMERA, decoded as livo-convert rosbag does) and\n"
                 "the suite to ROS (LIVO_ODOMETRY -> P/odometry + /tf, LIVO_REGISTERED_SCAN -> P/registered_scan and\n"
                 "the decimated map P/map, statistics -> /diagnostics). Stops on SIGINT / SIGTERM.");
  ProcessArgs args;
  BridgeOptions opt;
  addProcessOptions(cl, args);
  addRosInputOptions(cl, opt.input);
  addBridgeOptions(cl, opt);
  cl.epilog("Topics: each role takes the named topic, or the only topic of a matching type as it appears in the\n"
            "ROS graph; a missing master or topic is waited for, never fatal. IMU accelerations in g (Livox) are\n"
            "detected from the first 200 samples, which are held until then. --idle-exit counts LCM messages.");
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;

  try {
    ConfigFile file = ConfigFile::load(args.config);
    opt.channels.load(file.root().section("channels"));
    checkSectionsUsed(file, {"channels"});
    if (args.print_config) {
      printConfig(std::cout, cl.program(), file);
      return kExitOk;
    }
    checkRosInputOptions(opt.input);
  } catch (const std::exception& e) {
    std::cerr << "livo-ros-bridge: " << e.what() << "\n";
    return kExitUsage;
  }

  try {
    ros::M_string remappings;
    if (!opt.ros_master.empty()) remappings["__master"] = opt.ros_master;
    ros::init(remappings, opt.node_name, ros::init_options::NoSigintHandler | ros::init_options::NoRosout);
    ros::master::setRetryTimeout(ros::WallDuration(1.0));  // a registration never blocks longer
    resolveTopics(opt.input);
    opt.lcm_url = resolveLcmUrl(args.lcm_url);

    BridgeLog log(std::cerr);
    LcmNode lcm(opt.lcm_url, "livo-ros-bridge", &std::cerr);
    SensorInput lidar(RosRole::Lidar, opt, lcm, log), imu(RosRole::Imu, opt, lcm, log),
        camera(RosRole::Camera, opt, lcm, log);
    const std::vector<SensorInput*> inputs{&lidar, &imu, &camera};
    EstimatorOutputs outputs(opt, lcm, log);
    RosSession session(opt, inputs, outputs, log);
    Reporter reporter(opt, inputs, outputs, session, lcm, log);

    outputs.start();
    for (SensorInput* in : inputs) in->start();
    session.start();
    log.line("ROS master " + ros::master::getURI() + " <-> LCM: " + opt.channels.lidar + ", " + opt.channels.imu +
             ", " + opt.channels.camera + " out, " + opt.channels.odometry + ", " + opt.channels.registered_scan +
             ", " + opt.channels.estimator_stats + ", " + opt.channels.map_stats + " in on " + opt.lcm_url);
    const LcmNode::SpinEnd end = lcm.spin(args.idle_exit_s, [&] { reporter.poll(); });
    log.line(end == LcmNode::SpinEnd::kIdle ? "no LCM message for --idle-exit seconds, stopping"
                                            : std::string(stopSignal() ? strsignal(stopSignal()) : "stop requested") +
                                                  ", stopping");

    // Clean stop: no new registrations, the messages in progress finish, the IMU samples held for the unit
    // decision go out, the LCM -> ROS queue is published, then roscpp unregisters.
    session.stop();
    for (SensorInput* in : inputs) in->stop();
    for (SensorInput* in : inputs) in->finish();
    outputs.stop();
    std::cout << reporter.summary() << std::flush;
    ros::shutdown();
  } catch (const std::exception& e) {
    std::cerr << "livo-ros-bridge: error: " << e.what() << "\n";
    return kExitRunError;
  }
  return kExitOk;
}
