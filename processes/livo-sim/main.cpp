// livo-sim (--scenario config/sim/NAME.yaml | --random SEED) --out LOG.lcm --gt GT.tum [--rig RIG.yaml] [--seed N]
//          [--duration S] [--threads N] [--progress] [--quiet]
// Runs a simulator scenario (libs/sim) and writes an LCM log (LIVO_IMU, LIVO_LIDAR, LIVO_CAMERA in time
// order, log timestamps = sensor times), the ground-truth IMU trajectory (TUM) and a rig config.
#include "livo/cli/command_line.hpp"
#include "livo/cli/progress.hpp"
#include "livo/common/config.hpp"
#include "livo/common/timing.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/log.hpp"
#include "livo/sim/random_scenario.hpp"
#include "livo/sim/simulator.hpp"

#include <cinttypes>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

namespace {

const char* kDescription =
    "Simulates a LiDAR + IMU + camera rig moving through a synthetic world and writes:\n"
    "  LOG.lcm  LCM log with LIVO_IMU, LIVO_LIDAR and LIVO_CAMERA (Gray8) in time order, each event's\n"
    "           log timestamp equal to its message utime (sensor time)\n"
    "  GT.tum   ground-truth IMU pose at every IMU sample: 't x y z qx qy qz qw' (t in s, 9 decimals)\n"
    "Scenario keys: config/sim/README.md. Same scenario and seed: same bytes.";

struct Args {
  std::string scenario, out, gt, rig, scenario_out;
  std::int64_t random = -1;
  bool quiet = false, progress = false;
  std::int64_t seed = 0;
  double duration = 0.0;
  int threads = 2;
};

void addOptions(livo::CommandLine& cl, Args& a) {
  cl.text("--scenario", &a.scenario, "FILE", "scenario YAML (a scenario error exits with 2); or --random");
  cl.count("--random", &a.random, "SEED",
           "draw a complete scenario (world, LiDAR, IMU, camera, motion, start) from the random-rig distribution "
           "of config/sim/README.md instead of --scenario; 30 s unless --duration")
      .defaultText("off");
  cl.text("--scenario-out", &a.scenario_out, "FILE", "also write the scenario that ran as YAML (with --random: the drawn rig)");
  cl.text("--out", &a.out, "FILE", "LCM log to write").required();
  cl.text("--gt", &a.gt, "FILE", "ground-truth TUM file to write").required();
  cl.text("--rig", &a.rig, "FILE", "also write the rig config for livo-run (config/README.md schema)");
  cl.count("--seed", &a.seed, "N", "override the scenario's seed").defaultText("the scenario's seed");
  cl.number("--duration", &a.duration, "S", "override the scenario's duration", 0.0, true)
      .unit("s")
      .defaultText("the scenario's duration_s");
  cl.integer("--threads", &a.threads, "N", "threads for camera rendering and LiDAR (the output does not depend on it)",
             1, 16);
  livo::addProgressOption(cl, &a.progress);
  cl.flag("--quiet", &a.quiet, "no progress line and no summary on stderr");
}

// "t x y z qx qy qz qw" with t printed exactly from the microsecond stamp.
void writeTumLine(std::FILE* f, livo::Utime utime, const livo::Pose& T) {
  const auto q = livo::poseToArray(T);
  const long long sec = utime / 1000000, usec = utime % 1000000;
  std::fprintf(f, "%lld.%06lld000 %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", sec, usec, q[0], q[1], q[2], q[3], q[4],
               q[5], q[6]);
}

/// Counts of what was written, for the summary line.
struct Written {
  std::uint64_t imu = 0, scans = 0, images = 0, points = 0, bytes = 0;
};

/// One simulator event into the log (and the IMU's ground truth into the TUM file).
void writeEvent(const livo::sim::SimEvent& ev, livo::LogWriter& log, std::FILE* gt, Written& n) {
  switch (ev.kind) {
    case livo::sim::SimEvent::Kind::Imu: {
      const auto msg = livo::toMsg(ev.imu);
      log.write("LIVO_IMU", ev.utime, msg);
      n.bytes += static_cast<std::uint64_t>(msg.getEncodedSize());
      writeTumLine(gt, ev.utime, ev.imu_truth.T_world_imu);
      ++n.imu;
      break;
    }
    case livo::sim::SimEvent::Kind::Lidar: {
      const auto msg = livo::toMsg(ev.scan);
      log.write("LIVO_LIDAR", ev.utime, msg);
      n.bytes += static_cast<std::uint64_t>(msg.getEncodedSize());
      n.points += ev.scan.points.size();
      ++n.scans;
      break;
    }
    case livo::sim::SimEvent::Kind::Image: {
      const auto msg = livo::toMsg(ev.image);
      log.write("LIVO_CAMERA", ev.utime, msg);
      n.bytes += static_cast<std::uint64_t>(msg.getEncodedSize());
      ++n.images;
      break;
    }
  }
}

void printSummary(const livo::sim::Simulator& sim, double duration, double wall_s, const Written& n) {
  const auto& st = sim.lidarStats();
  std::fprintf(stderr,
               "livo-sim: %.1f s simulated in %.1f s wall: %llu IMU, %llu scans (%.0f points/scan; no return %.1f%%, "
               "blind %.1f%%, grazing %.1f%%), %llu images, %.1f MB of messages\n",
               duration, wall_s, static_cast<unsigned long long>(n.imu), static_cast<unsigned long long>(n.scans),
               n.scans ? static_cast<double>(n.points) / n.scans : 0.0, st.rays ? 100.0 * st.no_return / st.rays : 0.0,
               st.rays ? 100.0 * st.blind / st.rays : 0.0, st.rays ? 100.0 * st.grazing / st.rays : 0.0,
               static_cast<unsigned long long>(n.images), static_cast<double>(n.bytes) / 1e6);
}

/// The scenario with the command-line overrides; throws livo::ConfigError naming the key.
livo::sim::SimScenario loadScenario(const Args& a, const livo::CommandLine& cl) {
  livo::sim::SimScenario sc;
  if (cl.given("--random")) {
    const auto drawn = livo::sim::drawRandomScenario(static_cast<std::uint64_t>(a.random),
                                                     cl.given("--duration") ? a.duration : 30.0);
    sc = livo::sim::parseScenario(drawn.yaml);
    sc.source = "random rig " + std::to_string(a.random);
    if (!a.quiet) std::cerr << "livo-sim: random rig " << a.random << ": " << drawn.summary << "\n";
    if (!a.scenario_out.empty()) {
      std::ofstream out(a.scenario_out);
      if (!(out << drawn.yaml) || !out.flush()) throw livo::ConfigError(a.scenario_out + ": cannot write");
    }
  } else {
    sc = livo::sim::loadScenarioFile(a.scenario);
    if (!a.scenario_out.empty()) {
      std::ifstream in(a.scenario);
      std::ofstream out(a.scenario_out);
      if (!(out << in.rdbuf()) || !out.flush()) throw livo::ConfigError(a.scenario_out + ": cannot write");
    }
  }
  if (cl.given("--seed")) sc.seed = a.seed;
  if (cl.given("--duration")) sc.duration_s = a.duration;
  sc.validate();
  return sc;
}

int run(const Args& a, const livo::sim::SimScenario& sc) {
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
               sc.source.c_str(), static_cast<long long>(sc.seed));
  livo::LogWriter log(a.out);

  livo::sim::SimEvent ev;
  Written n;
  const double duration = sc.duration_s;
  livo::ProgressLine progress("livo-sim", "messages", livo::progressMode(a.progress, a.quiet));
  while (sim.next(ev)) {
    writeEvent(ev, log, gt, n);
    progress.update(sim.relTime(ev.utime) / duration, static_cast<double>(log.eventsWritten()));
  }
  progress.update(1.0, static_cast<double>(log.eventsWritten()));  // the last event comes before duration_s
  progress.finish();
  log.flush();
  if (std::fclose(gt) != 0) throw std::runtime_error(a.gt + ": write failed");
  if (!a.quiet) printSummary(sim, duration, wall.elapsedMs() * 1e-3, n);
  return livo::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  livo::CommandLine cl("livo-sim", kDescription);
  addOptions(cl, args);
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;
  if (cl.given("--random") == cl.given("--scenario")) {
    std::cerr << "livo-sim: give exactly one of --scenario FILE and --random SEED\ntry 'livo-sim --help'\n";
    return livo::kExitUsage;
  }
  livo::sim::SimScenario scenario;
  try {
    scenario = loadScenario(args, cl);
  } catch (const livo::ConfigError& e) {
    std::cerr << "livo-sim: " << e.what() << "\n";
    return livo::kExitUsage;
  }
  try {
    return run(args, scenario);
  } catch (const std::exception& e) {
    std::cerr << "\nlivo-sim: error: " << e.what() << "\n";
    return livo::kExitRunError;
  }
}
