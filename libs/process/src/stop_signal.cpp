#include "livo/process/stop_signal.hpp"

#include <atomic>
#include <csignal>

namespace livo {

namespace {

std::atomic<int> g_stop{0};  // 0: running; -1: requested from code; > 0: the signal number
static_assert(std::atomic<int>::is_always_lock_free, "the stop flag must be usable from a signal handler");

extern "C" void onStopSignal(int sig) {
  if (g_stop.load() != 0) {  // second signal: the default action (a stuck process still stops)
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  g_stop.store(sig);
}

}  // namespace

void installStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onStopSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a blocking wait returns with EINTR and the loop sees the flag
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

bool stopRequested() { return g_stop.load() != 0; }
int stopSignal() { return g_stop.load() > 0 ? g_stop.load() : 0; }
void requestStop() { g_stop.store(-1); }
void clearStopRequest() { g_stop.store(0); }

}  // namespace livo
