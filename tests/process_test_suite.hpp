// The demo scenario simulated once per test executable, and the suite's four processes (map server,
// estimator, preprocess, exporter) started in a network namespace, for the tests that watch a running
// suite from outside (test_viewer_screenshot, test_process_spy).
#pragma once

#include "process_test_children.hpp"
#include "process_test_files.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>
#include <memory>
#include <string>

namespace livo::test {

/// config/sim/NAME.yaml simulated for `duration_s` into `dir` (NAME.lcm, gt.tum, rig.yaml).
struct SimulatedScenario {
  std::string dir, log, gt, rig, error;
  bool ok = false;
  SimulatedScenario(const std::string& d, const std::string& name, double duration_s)
      : dir(d), log(d + "/" + name + ".lcm"), gt(d + "/gt.tum"), rig(d + "/rig.yaml") {
    const std::string cmd = kBin + "/livo-sim --scenario " + std::string(LIVO_SOURCE_DIR) + "/config/sim/" + name + ".yaml --out " +
                            log + " --gt " + gt + " --rig " + rig + " --duration " + std::to_string(duration_s) +
                            " --quiet > " + dir + "/sim.txt 2>&1";
    ok = std::system(cmd.c_str()) == 0;
    if (!ok) error = "livo-sim failed: " + readFile(dir + "/sim.txt");
  }
};

/// config/sim/demo.yaml simulated for `duration_s` into `dir` (demo.lcm, gt.tum, rig.yaml).
struct SimulatedDemo : SimulatedScenario {
  SimulatedDemo(const std::string& d, double duration_s) : SimulatedScenario(d, "demo", duration_s) {}
};

/// The four processes in `ns`, logs in `out`; each has subscribed once the constructor returns.
struct FourProcesses {
  const Netns& ns;
  std::string out;
  std::unique_ptr<Child> mapserver, estimator, preprocess, exporter;

  FourProcesses(const Netns& n, const std::string& rig, const std::string& out_dir) : ns(n), out(out_dir) {
    mapserver = start({kBin + "/livo-mapserver", "--config", rig, "--lcm-url", kUrl}, "mapserver");
    estimator = start({kBin + "/livo-estimator", "--config", rig, "--lcm-url", kUrl, "--idle-exit", "6"}, "estimator");
    preprocess = start({kBin + "/livo-preprocess", "--config", rig, "--lcm-url", kUrl, "--idle-exit", "3"}, "preprocess");
    exporter = start({kBin + "/livo-exporter", "--config", rig, "--lcm-url", kUrl, "--out", out + "/export",
                      "--idle-exit", "10"},
                     "exporter");
    for (const char* name : {"mapserver", "estimator", "preprocess", "exporter"}) awaitReady(log(name));
  }
  std::string log(const std::string& name) const { return out + "/" + name + ".txt"; }
  std::unique_ptr<Child> start(const std::vector<std::string>& argv, const std::string& name) const {
    return std::make_unique<Child>(ns.exec(argv), log(name));
  }
  /// A process prints "... on URL" once it has subscribed.
  static void awaitReady(const std::string& log_path) {
    EXPECT_TRUE(waitUntil([&] { return readFile(log_path).find(" on " + kUrl) != std::string::npos; }, 60))
        << log_path << ":\n" << readFile(log_path);
  }
  std::unique_ptr<Child> play(const std::string& lcm_log) const {
    return std::make_unique<Child>(ns.exec({"lcm-logplayer", "--lcm-url=" + kUrl, "--speed=1", lcm_log}), log("player"));
  }
  /// Waits for the idle exits of the chain, then stops the map server.
  void finish() {
    EXPECT_EQ(preprocess->wait(120), 0) << readFile(log("preprocess"));
    EXPECT_EQ(estimator->wait(120), 0) << readFile(log("estimator"));
    EXPECT_EQ(exporter->wait(120), 0) << readFile(log("exporter"));
    mapserver->signal(SIGINT);
    EXPECT_EQ(mapserver->wait(60), 0) << readFile(log("mapserver"));
  }
};

}  // namespace livo::test
