// livo-convert: dataset folders to LCM logs (thin CLI around libs/datasets).
//   livo-convert euroc DIR --out LOG.lcm [--rig RIG.yaml] [--start S] [--end S] [--imu-margin S] ...
//   livo-convert kitti DIR --out LOG.lcm [--fields auto|xyz|xyzi] [--rate-hz HZ] [--start-time S] ...
//   livo-convert rosbag BAG --out LOG.lcm [--lidar-topic T] [--imu-topic T] [--image-topic T] ...
// Exit codes: 0 success, 1 bad input or I/O error (message names the file and line; a bag conversion that
// stopped early at a corrupt chunk keeps the log of what came before), 2 usage error.
#include "cli.hpp"
#include "livo/datasets/euroc.hpp"
#include "livo/datasets/kitti.hpp"
#include "livo/datasets/rosbag.hpp"

#include <exception>
#include <fstream>
#include <iostream>
#include <string>

namespace {

using livo::CommandLine;
using livo_convert::CommonArgs;
using livo_convert::progressLine;

/// The euroc command's values beyond livo::EurocOptions (window limits are optional there).
struct EurocArgs {
  std::string rig;
  double start_s = 0.0, end_s = 0.0;
};

void addEurocOptions(CommandLine& cl, livo::EurocOptions& opt, EurocArgs& a) {
  cl.text("--rig", &a.rig, "RIG.yaml", "also write a rig config (imu + camera sections) from the sensor.yaml files");
  cl.number("--start", &a.start_s, "S",
            "image window start: relative to the first image, or absolute sensor time when >= 1e8 s")
      .unit("s")
      .defaultText("the first image");
  cl.number("--end", &a.end_s, "S", "image window end (as --start)").unit("s").defaultText("the last image");
  cl.number("--imu-margin", &opt.imu_margin_s, "S",
            "IMU kept S seconds before the window start and after its end (the IMU csv may cover much more than "
            "the images; it is clipped to this window)",
            0.0)
      .unit("s");
  cl.text("--camera", &opt.camera, "NAME", "camera folder");
  cl.text("--imu", &opt.imu, "NAME", "IMU folder");
  cl.text("--imu-channel", &opt.imu_channel, "CH", "output channel of the IMU");
  cl.text("--camera-channel", &opt.camera_channel, "CH", "output channel of the images");
}

void addKittiOptions(CommandLine& cl, livo::KittiOptions& opt, bool& no_times) {
  cl.choice("--fields", &opt.fields,
            {{"auto", livo::PointFields::Auto}, {"xyz", livo::PointFields::Xyz}, {"xyzi", livo::PointFields::Xyzi}},
            "float32 x,y,z[,intensity] records; auto: the record size that fits every file and times file, an error "
            "when ambiguous");
  cl.number("--rate-hz", &opt.rate_hz, "HZ", "scan rate, scan i starts at start + i / rate", 0.0, true).unit("Hz");
  cl.number("--start-time", &opt.start_time_s, "S", "sensor time of the first scan").unit("s");
  cl.text("--prefix", &opt.prefix, "P", "only scan files whose name starts with P (e.g. raw_)");
  cl.text("--times-prefix", &opt.times_prefix, "P", "per-point time files P<id>.bin paired with <series><id>.bin");
  cl.flag("--no-times", &no_times, "ignore per-point time files");
  cl.choice("--synth-times", &opt.synth_times, {{"none", livo::SynthTimes::None}, {"azimuth", livo::SynthTimes::Azimuth}},
            "offsets of scans without time files (none: 0)");
  cl.text("--sensor", &opt.sensor, "NAME", "lidar_scan_t.sensor");
  cl.text("--lidar-channel", &opt.lidar_channel, "CH", "output channel of the scans");
}

int runEuroc(const CommandLine& cl, const CommonArgs& c, livo::EurocOptions opt, const EurocArgs& a) {
  if (cl.given("--start")) opt.start_s = a.start_s;
  if (cl.given("--end")) opt.end_s = a.end_s;
  opt.progress = progressLine(c.progressMode(), "images");
  const livo::ConversionSummary summary = livo::convertEuroc(c.in, c.out, opt);
  opt.progress = nullptr;  // ends the progress line
  if (!a.rig.empty()) {
    const std::string mav = livo::eurocMavDir(c.in, opt);
    const std::string text = livo::eurocRigYaml(livo::readEurocCalibration(mav, opt), mav);
    std::ofstream f(a.rig);
    if (!(f << text)) throw livo::DatasetError(a.rig + ": cannot write the rig config");
  }
  std::cout << "livo-convert euroc: " << summary.describe();
  if (!a.rig.empty()) std::cout << "  rig config: " << a.rig << "\n";
  return livo::kExitOk;
}

int runKitti(const CommonArgs& c, livo::KittiOptions opt, bool no_times) {
  if (no_times) opt.use_times = false;
  opt.progress = progressLine(c.progressMode(), "scans");
  const livo::ConversionSummary summary = livo::convertKitti(c.in, c.out, opt);
  opt.progress = nullptr;  // ends the progress line
  std::cout << "livo-convert kitti: " << summary.describe();
  return livo::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cl("livo-convert", "Converts datasets to LCM logs (LIVO_IMU, LIVO_LIDAR, LIVO_CAMERA).");
  CommonArgs common;
  livo::EurocOptions euroc;
  EurocArgs euroc_args;
  livo::KittiOptions kitti;
  bool no_times = false;
  livo::RosbagOptions bag;
  CommandLine& euroc_cl = cl.command("euroc", "EuRoC/ASL folder (DIR or DIR/mav0 holding cam0/ and imu0/) -> LIVO_IMU + LIVO_CAMERA");
  livo_convert::addCommonOptions(euroc_cl, common, "DIR", "EuRoC/ASL folder");
  addEurocOptions(euroc_cl, euroc, euroc_args);
  CommandLine& kitti_cl = cl.command("kitti", "KITTI-style float32 .bin scans (DIR/*.bin, DIR/<sub>/points.bin, or one file) -> LIVO_LIDAR");
  livo_convert::addCommonOptions(kitti_cl, common, "DIR", "folder of .bin scans, or one .bin file");
  addKittiOptions(kitti_cl, kitti, no_times);
  CommandLine& bag_cl = cl.command("rosbag", "ROS 1 bag (uncompressed, bz2 or lz4 chunks) -> LIVO_LIDAR + LIVO_IMU + LIVO_CAMERA");
  livo_convert::addCommonOptions(bag_cl, common, "BAG", "ROS 1 bag (times and formats: README \"Running on public datasets\")");
  livo_convert::addRosbagOptions(bag_cl, bag);
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;

  try {
    if (cl.commandName() == "euroc") return runEuroc(euroc_cl, common, euroc, euroc_args);
    if (cl.commandName() == "kitti") return runKitti(common, kitti, no_times);
    return livo_convert::runRosbag(common.in, common.out, bag, common.progressMode());
  } catch (const std::exception& e) {
    std::cerr << "livo-convert: error: " << e.what() << "\n";
    return livo::kExitRunError;
  }
}
