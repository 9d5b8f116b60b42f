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

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace {

using livo_convert::parseNumber;
using livo_convert::parseRosbagOption;
using livo_convert::Progress;
using livo_convert::runRosbag;
using livo_convert::UsageError;

const char* kUsage = R"(usage: livo-convert FORMAT DIR|BAG --out LOG.lcm [options]

Formats:
  euroc   EuRoC/ASL folder (DIR or DIR/mav0 holding cam0/ and imu0/) -> LIVO_IMU + LIVO_CAMERA
  kitti   KITTI-style float32 .bin scans (DIR/*.bin, DIR/<sub>/points.bin, or one file) -> LIVO_LIDAR
  rosbag  ROS 1 bag (uncompressed, bz2 or lz4 chunks) -> LIVO_LIDAR + LIVO_IMU + LIVO_CAMERA

Common options:
  --out LOG.lcm          output log (required; overwritten; removed again if the conversion fails, except
                         a bag conversion stopped by a corrupt chunk, which keeps the events before it)
  --quiet                no progress line on stderr
  --help                 this text

euroc options:
  --rig RIG.yaml         also write a rig config (imu + camera sections) from the sensor.yaml files
  --start S, --end S     image window in seconds: relative to the first image, or absolute sensor time when
                         >= 1e8 s (default: all images)
  --imu-margin S         IMU kept S seconds before the window start and after its end (default 1). The IMU
                         csv may cover much more than the images; it is clipped to this window.
  --camera NAME          camera folder (default cam0)       --imu NAME   IMU folder (default imu0)
  --imu-channel CH       (default LIVO_IMU)                  --camera-channel CH   (default LIVO_CAMERA)

kitti options:
  --fields F             auto | xyz | xyzi  (float32 x,y,z[,intensity] records; default auto: the record
                         size that fits every file and times file, error when ambiguous)
  --rate-hz HZ           scan rate, scan i starts at start + i / rate (default 10)
  --start-time S         sensor time of the first scan in seconds (default 0)
  --prefix P             only scan files whose name starts with P (e.g. raw_)
  --times-prefix P       per-point time files P<id>.bin paired with <series><id>.bin (default times_)
  --no-times             ignore per-point time files
  --synth-times M        none | azimuth: offsets of scans without time files (default none -> 0)
  --sensor NAME          lidar_scan_t.sensor (default generic)
  --lidar-channel CH     (default LIVO_LIDAR)

rosbag options (times and formats: README "Running on public datasets"):
  --lidar-topic T        sensor_msgs/PointCloud2 or livox_ros_driver(2)/CustomMsg topic
  --imu-topic T          sensor_msgs/Imu topic
  --image-topic T        sensor_msgs/Image or sensor_msgs/CompressedImage topic
                         Default for each: the only topic of a matching type; "none" skips the role.
  --sensor NAME          lidar_scan_t.sensor (default avia for Livox CustomMsg, else generic)
  --point-time-field F   PointCloud2 per-point time field, or none (default: the first of time, t,
                         timestamp, offset_time; integer fields are ns, floating ones s; values of 1e5 s
                         and more are absolute times, smaller ones offsets from the header stamp)
  --imu-accel-unit U     auto | g | mps2 (default auto: median |a| of the first 200 samples in 0.7..1.3
                         means g, converted with --gravity)
  --gravity G            m/s^2 per g (default 9.80665)
  --mono16-bits B        convert mono16/16UC1 images to GRAY8 keeping the top 8 of B significant bits
                         (9..16); default: keep GRAY16
  --reorder-window S     seconds of sensor time an event may arrive late (default 1)
  --max-scan-span S      skip scans whose points span more than S seconds (default 1)
  --skip-bad             skip malformed messages (counted) instead of stopping at the first
  --imu-channel CH, --camera-channel CH, --lidar-channel CH   output channels
)";

int run(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  for (const auto& a : args)
    if (a == "--help" || a == "-h") {
      std::cout << kUsage;
      return 0;
    }
  std::vector<std::string> positional;
  std::string out, rig;
  bool quiet = false;
  livo::EurocOptions euroc;
  livo::KittiOptions kitti;
  livo::RosbagOptions bag;
  std::vector<std::pair<std::string, std::string>> used;  // flag, formats it applies to
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw UsageError(a + ": missing value");
      return args[++i];
    };
    auto only = [&](const char* formats) { used.emplace_back(a, formats); };
    if (a.rfind("--", 0) != 0) {
      positional.push_back(a);
    } else if (a == "--out") {
      out = value();
    } else if (a == "--quiet") {
      quiet = true;
    } else if (a == "--rig") {
      rig = value(), only("euroc");
    } else if (a == "--start") {
      euroc.start_s = parseNumber(a, value()), only("euroc");
    } else if (a == "--end") {
      euroc.end_s = parseNumber(a, value()), only("euroc");
    } else if (a == "--imu-margin") {
      euroc.imu_margin_s = parseNumber(a, value()), only("euroc");
    } else if (a == "--camera") {
      euroc.camera = value(), only("euroc");
    } else if (a == "--imu") {
      euroc.imu = value(), only("euroc");
    } else if (a == "--imu-channel") {
      euroc.imu_channel = bag.imu_channel = value(), only("euroc rosbag");
    } else if (a == "--camera-channel") {
      euroc.camera_channel = bag.camera_channel = value(), only("euroc rosbag");
    } else if (a == "--fields") {
      const std::string f = value();
      if (f == "auto") kitti.fields = livo::PointFields::Auto;
      else if (f == "xyz") kitti.fields = livo::PointFields::Xyz;
      else if (f == "xyzi") kitti.fields = livo::PointFields::Xyzi;
      else throw UsageError("--fields: expected auto, xyz or xyzi, got '" + f + "'");
      only("kitti");
    } else if (a == "--rate-hz") {
      kitti.rate_hz = parseNumber(a, value()), only("kitti");
    } else if (a == "--start-time") {
      kitti.start_time_s = parseNumber(a, value()), only("kitti");
    } else if (a == "--prefix") {
      kitti.prefix = value(), only("kitti");
    } else if (a == "--times-prefix") {
      kitti.times_prefix = value(), only("kitti");
    } else if (a == "--no-times") {
      kitti.use_times = false, only("kitti");
    } else if (a == "--synth-times") {
      const std::string m = value();
      if (m == "none") kitti.synth_times = livo::SynthTimes::None;
      else if (m == "azimuth") kitti.synth_times = livo::SynthTimes::Azimuth;
      else throw UsageError("--synth-times: expected none or azimuth, got '" + m + "'");
      only("kitti");
    } else if (a == "--sensor") {
      kitti.sensor = bag.sensor = value(), only("kitti rosbag");
    } else if (a == "--lidar-channel") {
      kitti.lidar_channel = bag.lidar_channel = value(), only("kitti rosbag");
    } else if (!parseRosbagOption(args, i, bag)) {
      throw UsageError("unknown option " + a);
    } else {
      only("rosbag");
    }
  }
  if (positional.size() != 2) throw UsageError("expected FORMAT and DIR (or BAG)");
  const std::string& format = positional[0];
  const std::string& dir = positional[1];
  if (format != "euroc" && format != "kitti" && format != "rosbag")
    throw UsageError("unknown format '" + format + "' (known: euroc, kitti, rosbag)");
  if (out.empty()) throw UsageError("--out LOG.lcm is required");
  for (const auto& [flag, formats] : used)
    if ((" " + formats + " ").find(" " + format + " ") == std::string::npos)
      throw UsageError(flag + " does not apply to format " + format);

  livo::ConversionSummary summary;
  if (format == "euroc") {
    euroc.progress = Progress(quiet, "images");
    summary = livo::convertEuroc(dir, out, euroc);
    if (!rig.empty()) {
      const std::string mav = livo::eurocMavDir(dir, euroc);
      const std::string text = livo::eurocRigYaml(livo::readEurocCalibration(mav, euroc), mav);
      std::ofstream f(rig);
      if (!(f << text)) throw livo::DatasetError(rig + ": cannot write the rig config");
    }
  } else if (format == "kitti") {
    kitti.progress = Progress(quiet, "scans");
    summary = livo::convertKitti(dir, out, kitti);
  } else {
    return runRosbag(dir, out, bag, quiet);
  }
  std::cout << "livo-convert " << format << ": " << summary.describe();
  if (!rig.empty()) std::cout << "  rig config: " << rig << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << "livo-convert: " << e.what() << "\n(see livo-convert --help)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "livo-convert: error: " << e.what() << "\n";
    return 1;
  }
}
