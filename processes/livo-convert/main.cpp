// livo-convert: dataset folders to LCM logs (thin CLI around libs/datasets).
//   livo-convert euroc DIR --out LOG.lcm [--rig RIG.yaml] [--start S] [--end S] [--imu-margin S] ...
//   livo-convert kitti DIR --out LOG.lcm [--fields auto|xyz|xyzi] [--rate-hz HZ] [--start-time S] ...
// Exit codes: 0 success, 1 bad input or I/O error (message names the file and line), 2 usage error.
#include "livo/datasets/euroc.hpp"
#include "livo/datasets/kitti.hpp"

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

const char* kUsage = R"(usage: livo-convert FORMAT DIR --out LOG.lcm [options]

Formats:
  euroc   EuRoC/ASL folder (DIR or DIR/mav0 holding cam0/ and imu0/) -> LIVO_IMU + LIVO_CAMERA
  kitti   KITTI-style float32 .bin scans (DIR/*.bin, DIR/<sub>/points.bin, or one file) -> LIVO_LIDAR
  (ROS bags are not supported yet.)

Common options:
  --out LOG.lcm          output log (required; overwritten; removed again if the conversion fails)
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
)";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

double parseNumber(const std::string& flag, const std::string& s) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v) || errno == ERANGE)
    throw UsageError(flag + ": expected a number, got '" + s + "'");
  return v;
}

/// Progress on stderr: one line rewritten in place on a terminal, a line per 25 % otherwise.
class Progress {
 public:
  Progress(bool quiet, std::string what) : quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0), what_(std::move(what)) {}
  void operator()(std::uint64_t done, std::uint64_t total) {
    if (quiet_ || total == 0) return;
    const int pct = static_cast<int>(100 * done / total);
    const int step = tty_ ? 1 : 25;
    if (pct / step == last_ / step && done != total) return;
    last_ = pct;
    std::fprintf(stderr, "%slivo-convert: %llu/%llu %s (%d%%)%s", tty_ ? "\r" : "",
                 static_cast<unsigned long long>(done), static_cast<unsigned long long>(total), what_.c_str(), pct,
                 tty_ && done != total ? "" : "\n");
  }

 private:
  bool quiet_, tty_;
  std::string what_;
  int last_ = -1;
};

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
  std::vector<std::string> euroc_only, kitti_only;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw UsageError(a + ": missing value");
      return args[++i];
    };
    if (a.rfind("--", 0) != 0) {
      positional.push_back(a);
    } else if (a == "--out") {
      out = value();
    } else if (a == "--quiet") {
      quiet = true;
    } else if (a == "--rig") {
      rig = value(), euroc_only.push_back(a);
    } else if (a == "--start") {
      euroc.start_s = parseNumber(a, value()), euroc_only.push_back(a);
    } else if (a == "--end") {
      euroc.end_s = parseNumber(a, value()), euroc_only.push_back(a);
    } else if (a == "--imu-margin") {
      euroc.imu_margin_s = parseNumber(a, value()), euroc_only.push_back(a);
    } else if (a == "--camera") {
      euroc.camera = value(), euroc_only.push_back(a);
    } else if (a == "--imu") {
      euroc.imu = value(), euroc_only.push_back(a);
    } else if (a == "--imu-channel") {
      euroc.imu_channel = value(), euroc_only.push_back(a);
    } else if (a == "--camera-channel") {
      euroc.camera_channel = value(), euroc_only.push_back(a);
    } else if (a == "--fields") {
      const std::string f = value();
      if (f == "auto") kitti.fields = livo::PointFields::Auto;
      else if (f == "xyz") kitti.fields = livo::PointFields::Xyz;
      else if (f == "xyzi") kitti.fields = livo::PointFields::Xyzi;
      else throw UsageError("--fields: expected auto, xyz or xyzi, got '" + f + "'");
      kitti_only.push_back(a);
    } else if (a == "--rate-hz") {
      kitti.rate_hz = parseNumber(a, value()), kitti_only.push_back(a);
    } else if (a == "--start-time") {
      kitti.start_time_s = parseNumber(a, value()), kitti_only.push_back(a);
    } else if (a == "--prefix") {
      kitti.prefix = value(), kitti_only.push_back(a);
    } else if (a == "--times-prefix") {
      kitti.times_prefix = value(), kitti_only.push_back(a);
    } else if (a == "--no-times") {
      kitti.use_times = false, kitti_only.push_back(a);
    } else if (a == "--synth-times") {
      const std::string m = value();
      if (m == "none") kitti.synth_times = livo::SynthTimes::None;
      else if (m == "azimuth") kitti.synth_times = livo::SynthTimes::Azimuth;
      else throw UsageError("--synth-times: expected none or azimuth, got '" + m + "'");
      kitti_only.push_back(a);
    } else if (a == "--sensor") {
      kitti.sensor = value(), kitti_only.push_back(a);
    } else if (a == "--lidar-channel") {
      kitti.lidar_channel = value(), kitti_only.push_back(a);
    } else {
      throw UsageError("unknown option " + a);
    }
  }
  if (positional.size() != 2) throw UsageError("expected FORMAT and DIR");
  const std::string& format = positional[0];
  const std::string& dir = positional[1];
  if (format != "euroc" && format != "kitti")
    throw UsageError("unknown format '" + format + "' (known: euroc, kitti; ROS bags are not supported yet)");
  if (out.empty()) throw UsageError("--out LOG.lcm is required");
  const auto& foreign = format == "euroc" ? kitti_only : euroc_only;
  if (!foreign.empty()) throw UsageError(foreign.front() + " does not apply to format " + format);

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
  } else {
    kitti.progress = Progress(quiet, "scans");
    summary = livo::convertKitti(dir, out, kitti);
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
