// livo-sim --scenario config/sim/NAME.yaml --out LOG.lcm --gt GT.tum [--rig RIG.yaml] [--seed N]
//          [--duration S] [--threads N] [--quiet]
// Runs a simulator scenario (libs/sim) and writes an LCM log (LIVO_IMU, LIVO_LIDAR, LIVO_CAMERA in time
// order, log timestamps = sensor times), the ground-truth IMU trajectory (TUM) and a rig config.
#include "livo/common/timing.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/log.hpp"
#include "livo/sim/simulator.hpp"

#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

namespace {

const char* kUsage =
    "usage: livo-sim --scenario config/sim/NAME.yaml --out LOG.lcm --gt GT.tum [options]\n"
    "\n"
    "Simulates a LiDAR + IMU + camera rig moving through a synthetic world and writes:\n"
    "  LOG.lcm  LCM log with LIVO_IMU, LIVO_LIDAR and LIVO_CAMERA (Gray8) in time order, each event's\n"
    "           log timestamp equal to its message utime (sensor time)\n"
    "  GT.tum   ground-truth IMU pose at every IMU sample: 't x y z qx qy qz qw' (t in s, 9 decimals)\n"
    "Scenario keys: config/sim/README.md. Same scenario and seed: same bytes.\n"
    "\n"
    "options:\n"
    "  --scenario FILE  scenario YAML (required)\n"
    "  --out FILE       LCM log to write (required)\n"
    "  --gt FILE        ground-truth TUM file to write (required)\n"
    "  --rig FILE       also write the rig config for livo-run (config/README.md schema)\n"
    "  --seed N         override the scenario's seed (N >= 0)\n"
    "  --duration S     override the scenario's duration in seconds\n"
    "  --threads N      threads for camera rendering and LiDAR (default 2; the output does not depend on it)\n"
    "  --quiet          no progress line on stderr\n"
    "  --help           this text\n"
    "Exit status: 0 on success, 1 on a scenario or I/O error, 2 on a usage error.\n";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Args {
  std::string scenario, out, gt, rig;
  bool has_seed = false, has_duration = false, quiet = false;
  std::int64_t seed = 0;
  double duration = 0.0;
  int threads = 2;
};

double parseNumber(const std::string& flag, const std::string& text) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(v))
    throw UsageError(flag + ": expected a number, got '" + text + "'");
  return v;
}

std::int64_t parseInteger(const std::string& flag, const std::string& text, std::int64_t lo, std::int64_t hi) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || v < lo || v > hi)
    throw UsageError(flag + ": expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                     "], got '" + text + "'");
  return v;
}

Args parseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(flag + ": missing value");
      return argv[++i];
    };
    if (flag == "--scenario") a.scenario = value();
    else if (flag == "--out") a.out = value();
    else if (flag == "--gt") a.gt = value();
    else if (flag == "--rig") a.rig = value();
    else if (flag == "--seed") { a.seed = parseInteger(flag, value(), 0, INT64_MAX); a.has_seed = true; }
    else if (flag == "--duration") {
      a.duration = parseNumber(flag, value());
      if (a.duration <= 0.0) throw UsageError("--duration: must be > 0");
      a.has_duration = true;
    } else if (flag == "--threads") a.threads = static_cast<int>(parseInteger(flag, value(), 1, 16));
    else if (flag == "--quiet") a.quiet = true;
    else throw UsageError("unknown option '" + flag + "'");
  }
  if (a.scenario.empty()) throw UsageError("--scenario is required");
  if (a.out.empty()) throw UsageError("--out is required");
  if (a.gt.empty()) throw UsageError("--gt is required");
  return a;
}

// "t x y z qx qy qz qw" with t printed exactly from the microsecond stamp.
void writeTumLine(std::FILE* f, livo::Utime utime, const livo::Pose& T) {
  const auto q = livo::poseToArray(T);
  const long long sec = utime / 1000000, usec = utime % 1000000;
  std::fprintf(f, "%lld.%06lld000 %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", sec, usec, q[0], q[1], q[2], q[3], q[4],
               q[5], q[6]);
}

int run(const Args& a) {
  livo::sim::SimScenario sc = livo::sim::loadScenarioFile(a.scenario);
  if (a.has_seed) sc.seed = a.seed;
  if (a.has_duration) sc.duration_s = a.duration;
  sc.validate();
  livo::sim::SimOptions opt;
  opt.threads = a.threads;
  livo::Stopwatch wall;
  livo::sim::Simulator sim(sc, opt);

  if (!a.rig.empty()) {
    std::ofstream rig(a.rig);
    if (!rig) throw std::runtime_error(a.rig + ": cannot open for writing");
    sim.writeRigConfig(rig);
    if (!rig.flush()) throw std::runtime_error(a.rig + ": write failed");
  }
  std::FILE* gt = std::fopen(a.gt.c_str(), "w");
  if (!gt) throw std::runtime_error(a.gt + ": cannot open for writing");
  std::fprintf(gt, "# ground truth of %s (seed %lld): IMU pose in the world, t x y z qx qy qz qw\n",
               a.scenario.c_str(), static_cast<long long>(sc.seed));
  livo::LogWriter log(a.out);

  livo::sim::SimEvent ev;
  std::uint64_t n_imu = 0, n_scans = 0, n_images = 0, n_points = 0, bytes = 0;
  double last_print = -1.0;
  const double duration = sc.duration_s;
  while (sim.next(ev)) {
    switch (ev.kind) {
      case livo::sim::SimEvent::Kind::Imu: {
        const auto msg = livo::toMsg(ev.imu);
        log.write("LIVO_IMU", ev.utime, msg);
        bytes += static_cast<std::uint64_t>(msg.getEncodedSize());
        writeTumLine(gt, ev.utime, ev.imu_truth.T_world_imu);
        ++n_imu;
        break;
      }
      case livo::sim::SimEvent::Kind::Lidar: {
        const auto msg = livo::toMsg(ev.scan);
        log.write("LIVO_LIDAR", ev.utime, msg);
        bytes += static_cast<std::uint64_t>(msg.getEncodedSize());
        n_points += ev.scan.points.size();
        ++n_scans;
        break;
      }
      case livo::sim::SimEvent::Kind::Image: {
        const auto msg = livo::toMsg(ev.image);
        log.write("LIVO_CAMERA", ev.utime, msg);
        bytes += static_cast<std::uint64_t>(msg.getEncodedSize());
        ++n_images;
        break;
      }
    }
    const double elapsed = wall.elapsedMs() * 1e-3;
    if (!a.quiet && elapsed - last_print >= 0.5) {
      last_print = elapsed;
      const double sim_t = sim.relTime(ev.utime);
      std::fprintf(stderr, "\rlivo-sim: %7.1f / %.1f s simulated (%3.0f%%), %6.0f events/s, %.1f MB   ", sim_t, duration,
                   100.0 * sim_t / duration, static_cast<double>(log.eventsWritten()) / std::max(elapsed, 1e-9),
                   static_cast<double>(bytes) / 1e6);
    }
  }
  log.flush();
  if (std::fclose(gt) != 0) throw std::runtime_error(a.gt + ": write failed");
  if (!a.quiet) {
    const auto& st = sim.lidarStats();
    std::fprintf(stderr,
                 "\rlivo-sim: %.1f s simulated in %.1f s wall: %llu IMU, %llu scans (%.0f points/scan; no return %.1f%%, "
                 "blind %.1f%%, grazing %.1f%%), %llu images, %.1f MB of messages\n",
                 duration, wall.elapsedMs() * 1e-3, static_cast<unsigned long long>(n_imu),
                 static_cast<unsigned long long>(n_scans), n_scans ? static_cast<double>(n_points) / n_scans : 0.0,
                 st.rays ? 100.0 * st.no_return / st.rays : 0.0, st.rays ? 100.0 * st.blind / st.rays : 0.0,
                 st.rays ? 100.0 * st.grazing / st.rays : 0.0, static_cast<unsigned long long>(n_images),
                 static_cast<double>(bytes) / 1e6);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      std::cout << kUsage;
      return 0;
    }
  Args args;
  try {
    args = parseArgs(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << "livo-sim: " << e.what() << "\n\n" << kUsage;
    return 2;
  }
  try {
    return run(args);
  } catch (const std::exception& e) {
    std::cerr << "\nlivo-sim: error: " << e.what() << "\n";
    return 1;
  }
}
