// An X server for the tests that open windows (livo-viewer, lcm-spy): Xvfb, in the test's network
// namespace when it has one (X clients there may reach it through its abstract socket too), on a
// display number it picks itself (-displayfd), so that tests running in parallel never collide.
#pragma once

#include "process_test_children.hpp"
#include "process_test_files.hpp"

#include <csignal>
#include <memory>
#include <string>

namespace livo::test {

struct XServer {
  bool ok = false;
  std::string why;      ///< why there is none
  std::string display;  ///< ":N"
  std::unique_ptr<Child> child;

  /// Starts Xvfb (screen `width` x `height` x 24) in `ns` (nullptr: here), its log and display number
  /// under `dir`.
  XServer(const Netns* ns, const std::string& dir, int width = 1280, int height = 1024) {
    if (!haveTool("Xvfb")) {
      why = "Xvfb missing (Debian package xvfb, installed by scripts/setup)";
      return;
    }
    const std::string number = dir + "/xvfb_display.txt", log = dir + "/xvfb.txt";
    const std::string screen = std::to_string(width) + "x" + std::to_string(height) + "x24";
    const std::vector<std::string> argv = {"sh", "-c",
                                           "exec Xvfb -displayfd 3 -screen 0 " + screen + " -nolisten tcp 3>'" + number + "'"};
    child = std::make_unique<Child>(ns ? ns->exec(argv) : argv, log);
    // Xvfb writes the display number and a newline once it accepts connections.
    const bool up = waitUntil([&] { return readFile(number).find('\n') != std::string::npos; }, 30);
    const std::string n = readFile(number);
    if (!up || n.empty() || n.find_first_not_of("0123456789\n") != std::string::npos) {
      why = "Xvfb did not start: " + readFile(log);
      return;
    }
    display = ":" + n.substr(0, n.find('\n'));
    ok = true;
  }
  ~XServer() {
    if (child) {
      child->signal(SIGTERM);
      child->wait(10);
    }
  }
  /// `argv` run with DISPLAY set to this server.
  std::vector<std::string> withDisplay(std::vector<std::string> argv) const {
    argv.insert(argv.begin(), {"env", "DISPLAY=" + display});
    return argv;
  }
};

}  // namespace livo::test
