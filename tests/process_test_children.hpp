// Child processes and a private network namespace for the tests that run the built binaries
// (no test traffic leaves the namespace's loopback device).
#pragma once

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fcntl.h>
#include <functional>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace livo::test {

inline const std::string kBin = std::string(LIVO_BINARY_DIR) + "/bin";
inline const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

inline void sleepS(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

/// Polls `cond` every 20 ms until it holds or `deadline_s` seconds have passed; returns whether it
/// held. Tests wait for a condition (a line in a log, poses written, a process gone) with a generous
/// deadline, never for a fixed time.
inline bool waitUntil(const std::function<bool()>& cond, double deadline_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(deadline_s);
  while (!cond()) {
    if (std::chrono::steady_clock::now() >= end) return cond();
    sleepS(0.02);
  }
  return true;
}

/// A child process with stdout and stderr in `log_path`.
struct Child {
  pid_t pid = -1;
  int status = -1;
  Child(const std::vector<std::string>& argv, const std::string& log_path) {
    pid = ::fork();
    if (pid == 0) {
      // Its own process group, so that a kill reaches what it started too (roscore's rosmaster and
      // rosout would otherwise outlive the test).
      ::setpgid(0, 0);
      const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        ::dup2(fd, 1);
        ::dup2(fd, 2);
      }
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execvp(args[0], args.data());
      ::_exit(127);
    }
  }
  /// Waits up to `timeout_s` (then SIGKILL); returns the exit code, or -signal.
  int wait(double timeout_s) {
    if (pid <= 0) return status;
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      int st = 0;
      if (::waitpid(pid, &st, WNOHANG) == pid) {
        pid = -1;
        return status = WIFEXITED(st) ? WEXITSTATUS(st) : -WTERMSIG(st);
      }
      sleepS(0.02);
    }
    killGroup();
    int st = 0;
    ::waitpid(pid, &st, 0);
    pid = -1;
    return status = 1000;  // timed out
  }
  void signal(int sig) const {
    if (pid > 0) ::kill(pid, sig);
  }
  /// SIGKILL to the child and everything in its process group.
  void killGroup() const {
    if (pid <= 0) return;
    ::kill(-pid, SIGKILL);
    ::kill(pid, SIGKILL);
  }
  ~Child() {
    if (pid > 0) {
      killGroup();
      ::waitpid(pid, nullptr, 0);
    }
  }
};

/// A private network namespace with multicast on its loopback device; `why` says why not.
struct Netns {
  std::string name = "livo_test_" + std::to_string(::getpid());
  bool ok = false;
  std::string why;
  Netns() {
    if (::geteuid() != 0) {
      why = "not root: cannot create a network namespace";
      return;
    }
    if (std::system(("ip netns add " + name + " 2>/dev/null").c_str()) != 0) {
      why = "'ip netns add' failed (no iproute2 or no namespace support)";
      return;
    }
    ok = std::system(("ip netns exec " + name + " ip link set lo up multicast on && ip netns exec " + name +
                      " ip route add 224.0.0.0/4 dev lo")
                         .c_str()) == 0;
    if (!ok) why = "could not enable multicast on the namespace's loopback device";
  }
  ~Netns() {
    if (::geteuid() == 0) (void)std::system(("ip netns del " + name + " 2>/dev/null").c_str());
  }
  std::vector<std::string> exec(std::vector<std::string> argv) const {
    argv.insert(argv.begin(), {"ip", "netns", "exec", name});
    return argv;
  }
};

inline bool haveTool(const std::string& tool) { return std::system(("command -v " + tool + " >/dev/null 2>&1").c_str()) == 0; }

}  // namespace livo::test
