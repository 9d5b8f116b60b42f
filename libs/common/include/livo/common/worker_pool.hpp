// A small pool of persistent worker threads for the per-frame loops (association, residuals), built so
// that results never depend on the number of threads:
//   - work is cut into blocks whose boundaries depend only on the item count and the caller's block
//     size, never on the thread count;
//   - every block writes only its own outputs; the caller reduces them in block order afterwards.
// Then a run with 1 thread and a run with 4 give bit-identical sums. Blocks are handed out in order
// to whichever thread is free (an atomic counter), so a slow thread does not hold the others back.
//
// The per-frame loops call the pool every few hundred microseconds with blocks of tens of
// microseconds, shorter than a sleeping thread takes to wake: so a worker that finished a call, and
// the caller waiting for the last blocks, first poll (yielding the core to any other runnable thread)
// for up to kSpinMicros before they sleep on a condition variable, as OpenMP runtimes do.
//
// forBlocks() is not reentrant: a block must not call forBlocks() on the same pool. One caller at a
// time (the pipeline's thread); the pool is neither copyable nor movable.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace livo {

/// The default of `--threads`: the machine's cores, at least 1 and at most 4 (beyond 4 the per-frame
/// loops are too short to gain).
int defaultThreadCount();

class WorkerPool {
 public:
  static constexpr int kMaxThreads = 64;
  static constexpr int kSpinMicros = 300;
  /// `threads` in 1..kMaxThreads (1: everything runs on the caller's thread, no worker is started);
  /// throws std::invalid_argument otherwise.
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  /// Threads that run blocks, the caller's included.
  int threads() const { return threads_; }

  /// Calls f(b) once for every block b in [0, blocks), on the caller's thread and the workers, and
  /// returns when all have finished. The first exception thrown by a block is rethrown here (the
  /// remaining blocks still run).
  void forBlocks(std::size_t blocks, const std::function<void(std::size_t)>& f);

  /// forBlocks over [0, n) cut into blocks of `block` items (the last one shorter): f(begin, end).
  void forRange(std::size_t n, std::size_t block, const std::function<void(std::size_t, std::size_t)>& f);

 private:
  void workerLoop();
  void runBlocks();

  const int threads_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;  ///< workers wait for a new generation
  std::condition_variable done_;  ///< the caller waits for the last block
  // Written under mutex_; atomic so that the polls may read them without it.
  std::atomic<std::size_t> generation_{0};   ///< one per forBlocks() call with workers
  std::atomic<std::size_t> outstanding_{0};  ///< blocks not finished + workers inside the generation
  bool stop_ = false;
  const std::function<void(std::size_t)>* task_ = nullptr;
  std::size_t blocks_ = 0;
  std::atomic<std::size_t> next_{0};
  std::exception_ptr error_;
};

/// Runs on `pool` when it is given, else serially on the caller's thread (the same blocks, the same
/// order of outputs).
inline void forRange(WorkerPool* pool, std::size_t n, std::size_t block,
                     const std::function<void(std::size_t, std::size_t)>& f) {
  if (pool) {
    pool->forRange(n, block, f);
    return;
  }
  for (std::size_t b = 0; b < n; b += block) f(b, b + block < n ? b + block : n);
}

}  // namespace livo
