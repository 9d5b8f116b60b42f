// An X server for the tests that open windows (livo-viewer, lcm-spy): Xvfb, in the test's network
// namespace when it has one (X clients there may reach it through its abstract socket too), on a
// display number it picks itself (-displayfd), so that tests running in parallel never collide.
#pragma once

#include "process_test_children.hpp"
#include "process_test_files.hpp"

#include <algorithm>
#include <csignal>
#include <cstddef>
#include <cstring>
#include <memory>
#include <string>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

namespace livo::test {

struct XServer {
  bool ok = false;
  std::string why;      ///< why there is none
  std::string display;  ///< ":N"
  std::unique_ptr<Child> child;

  /// Starts Xvfb (screen `width` x `height` x 24) in `ns` (nullptr: here), its log and display number
  /// under `dir`. A server that announced its display but does not answer on its socket (CI once saw
  /// a viewer fail to open an announced display) is replaced, up to three starts.
  XServer(const Netns* ns, const std::string& dir, int width = 1280, int height = 1024) {
    if (!haveTool("Xvfb")) {
      why = "Xvfb missing (Debian package xvfb, installed by scripts/setup)";
      return;
    }
    for (int attempt = 1; attempt <= 3 && !ok; ++attempt) {
      if (start(ns, dir, width, height)) break;
      why = "start " + std::to_string(attempt) + ": " + why;
      stop();
    }
  }
  /// What a failing test should print: the display, whether its Xvfb still runs, the lock file's
  /// owner and the server's log.
  std::string report() const {
    const std::string n = display.empty() ? "?" : display.substr(1);
    const bool running = child && child->pid > 0 && ::kill(child->pid, 0) == 0;
    return "Xvfb on :" + n + " (pid " + std::to_string(child ? child->pid : -1) + (running ? ", running" : ", gone") +
           "; /tmp/.X" + n + "-lock holds '" + readFile("/tmp/.X" + n + "-lock") + "'); its log: '" + readFile(log_) + "'";
  }
  ~XServer() { stop(); }
  /// `argv` run with DISPLAY set to this server.
  std::vector<std::string> withDisplay(std::vector<std::string> argv) const {
    argv.insert(argv.begin(), {"env", "DISPLAY=" + display});
    return argv;
  }

 private:
  std::string log_;

  bool start(const Netns* ns, const std::string& dir, int width, int height) {
    const std::string number = dir + "/xvfb_display.txt";
    log_ = dir + "/xvfb.txt";
    std::filesystem::remove(number);
    const std::string screen = std::to_string(width) + "x" + std::to_string(height) + "x24";
    const std::vector<std::string> argv = {"sh", "-c",
                                           "exec Xvfb -displayfd 3 -screen 0 " + screen + " -nolisten tcp 3>'" + number + "'"};
    child = std::make_unique<Child>(ns ? ns->exec(argv) : argv, log_);
    // Xvfb writes the display number and a newline once it accepts connections.
    const bool up = waitUntil([&] { return readFile(number).find('\n') != std::string::npos; }, 30);
    const std::string n = readFile(number);
    if (!up || n.empty() || n.find_first_not_of("0123456789\n") != std::string::npos) {
      why = "Xvfb did not start: " + readFile(log_);
      return false;
    }
    display = ":" + n.substr(0, n.find('\n'));
    // Its socket file is reachable from any namespace; its abstract socket only from its own.
    if (!connects("/tmp/.X11-unix/X" + display.substr(1), false) || (!ns && !connects("/tmp/.X11-unix/X" + display.substr(1), true))) {
      why = "Xvfb announced " + display + " but does not answer on its socket: " + report();
      return false;
    }
    ok = true;
    return true;
  }
  void stop() {
    if (child) {
      child->signal(SIGTERM);
      child->wait(10);
      child.reset();
    }
  }
  static bool connects(const std::string& path, bool abstract) {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return false;
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    const std::size_t off = abstract ? 1 : 0;
    std::memcpy(a.sun_path + off, path.c_str(), std::min(path.size(), sizeof(a.sun_path) - 1 - off));
    const socklen_t len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + off + path.size());
    const bool ok = ::connect(fd, reinterpret_cast<const sockaddr*>(&a), len) == 0;
    ::close(fd);
    return ok;
  }
};

}  // namespace livo::test
