// Runs f(part, parts) on `threads` threads (the caller's thread takes part 0). Every part must write
// only its own outputs, so that results do not depend on the number of threads or their timing.
#pragma once

#include <thread>
#include <vector>

namespace livo::sim {

template <class F>
void runParts(int threads, F&& f) {
  if (threads <= 1) {
    f(0, 1);
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads - 1));
  for (int t = 1; t < threads; ++t) pool.emplace_back([&f, t, threads] { f(t, threads); });
  f(0, threads);
  for (auto& th : pool) th.join();
}

}  // namespace livo::sim
