#include "livo/common/worker_pool.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

namespace livo {

namespace {

/// Polls `done` (yielding the core between polls) for up to WorkerPool::kSpinMicros; true when it
/// became true meanwhile.
template <class F>
bool pollFor(F&& done) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(WorkerPool::kSpinMicros);
  for (int i = 0;; ++i) {
    if (done()) return true;
    if ((i & 15) == 15 && std::chrono::steady_clock::now() > until) return false;
    std::this_thread::yield();
  }
}

}  // namespace

int defaultThreadCount() {
  const unsigned hw = std::thread::hardware_concurrency();  // 0 when unknown
  return std::clamp(static_cast<int>(hw), 1, 4);
}

WorkerPool::WorkerPool(int threads) : threads_(threads) {
  if (threads < 1 || threads > kMaxThreads)
    throw std::invalid_argument("thread count must be in 1.." + std::to_string(kMaxThreads) + " (got " +
                                std::to_string(threads) + ")");
  workers_.reserve(static_cast<std::size_t>(threads - 1));
  for (int t = 1; t < threads; ++t) workers_.emplace_back([this] { workerLoop(); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (auto& w : workers_) w.join();
}

void WorkerPool::runBlocks() {
  // task_ and blocks_ do not change while any thread is inside a generation (forBlocks waits for
  // outstanding_ == 0 before the next one), so reading them here needs no lock.
  std::size_t done = 0;
  for (;;) {
    const std::size_t b = next_.fetch_add(1, std::memory_order_relaxed);
    if (b >= blocks_) break;
    try {
      (*task_)(b);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
    ++done;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  outstanding_.fetch_sub(done, std::memory_order_release);
}

void WorkerPool::workerLoop() {
  std::size_t seen = 0;
  for (;;) {
    pollFor([&] { return generation_.load(std::memory_order_acquire) != seen; });
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || (task_ != nullptr && generation_ != seen); });
      if (stop_) return;
      seen = generation_;
      outstanding_.fetch_add(1, std::memory_order_relaxed);
    }
    runBlocks();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      outstanding_.fetch_sub(1, std::memory_order_release);
    }
    done_.notify_one();
  }
}

void WorkerPool::forBlocks(std::size_t blocks, const std::function<void(std::size_t)>& f) {
  if (blocks == 0) return;
  if (workers_.empty() || blocks == 1) {
    std::exception_ptr first;
    for (std::size_t b = 0; b < blocks; ++b) {
      try {
        f(b);
      } catch (...) {
        if (!first) first = std::current_exception();
      }
    }
    if (first) std::rethrow_exception(first);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    task_ = &f;
    blocks_ = blocks;
    next_.store(0, std::memory_order_relaxed);
    error_ = nullptr;
    outstanding_.store(blocks, std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  runBlocks();
  pollFor([&] { return outstanding_.load(std::memory_order_acquire) == 0; });
  std::exception_ptr error;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return outstanding_.load(std::memory_order_relaxed) == 0; });
    task_ = nullptr;
    error = error_;
    error_ = nullptr;
  }
  if (error) std::rethrow_exception(error);
}

void WorkerPool::forRange(std::size_t n, std::size_t block, const std::function<void(std::size_t, std::size_t)>& f) {
  if (block == 0) throw std::invalid_argument("WorkerPool::forRange: block size must be > 0");
  const std::size_t blocks = (n + block - 1) / block;
  forBlocks(blocks, [&](std::size_t b) {
    const std::size_t begin = b * block;
    f(begin, std::min(n, begin + block));
  });
}

}  // namespace livo
