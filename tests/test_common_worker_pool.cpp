// libs/common WorkerPool: every block runs exactly once per call, over many calls in a row (the
// generation hand-over between calls), block outputs summed in block order give the same bits for
// every thread count, exceptions reach the caller, bad thread counts are refused.
#include "livo/common/worker_pool.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

using namespace livo;

TEST(WorkerPool, EveryBlockRunsExactlyOncePerCall) {
  for (int threads : {1, 2, 3, 4, 8}) {
    WorkerPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    // Many short calls in a row: a worker late for one call must not run blocks of the next twice.
    for (int call = 0; call < 2000; ++call) {
      const std::size_t blocks = std::size_t(call % 17);  // 0 blocks and 1 block included
      std::vector<std::atomic<int>> runs(blocks);
      for (auto& r : runs) r = 0;
      pool.forBlocks(blocks, [&](std::size_t b) { runs[b].fetch_add(1); });
      for (std::size_t b = 0; b < blocks; ++b) ASSERT_EQ(runs[b].load(), 1) << "threads " << threads << " call " << call;
    }
  }
}

TEST(WorkerPool, ForRangeCoversTheRangeInFixedBlocks) {
  WorkerPool pool(3);
  for (std::size_t n : {0u, 1u, 7u, 8u, 9u, 1000u}) {
    std::vector<int> hits(n, 0);
    std::vector<std::pair<std::size_t, std::size_t>> ranges((n + 7) / 8);
    pool.forRange(n, 8, [&](std::size_t begin, std::size_t end) {
      ranges[begin / 8] = {begin, end};
      for (std::size_t i = begin; i < end; ++i) ++hits[i];
    });
    for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(hits[i], 1) << "n " << n << " i " << i;
    for (std::size_t b = 0; b < ranges.size(); ++b) {
      EXPECT_EQ(ranges[b].first, 8 * b);
      EXPECT_EQ(ranges[b].second, std::min(n, 8 * b + 8));
    }
  }
  EXPECT_THROW(pool.forRange(10, 0, [](std::size_t, std::size_t) {}), std::invalid_argument);
}

TEST(WorkerPool, BlockSumsInBlockOrderAreBitIdenticalForEveryThreadCount) {
  // Values over many magnitudes, so that any change of summation order changes the bits.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> e(-12.0, 12.0), s(-1.0, 1.0);
  std::vector<double> v(100000);
  for (auto& x : v) x = s(rng) * std::pow(10.0, e(rng));
  const auto blockSum = [&](WorkerPool* pool) {
    const std::size_t block = 256;
    std::vector<double> part((v.size() + block - 1) / block, 0.0);
    forRange(pool, v.size(), block, [&](std::size_t begin, std::size_t end) {
      double acc = 0;
      for (std::size_t i = begin; i < end; ++i) acc += v[i] * v[(i * 7919) % v.size()];
      part[begin / block] = acc;
    });
    double total = 0;
    for (double p : part) total += p;
    return total;
  };
  const double serial = blockSum(nullptr);
  for (int threads : {1, 2, 3, 4}) {
    WorkerPool pool(threads);
    for (int rep = 0; rep < 5; ++rep) {
      const double t = blockSum(&pool);
      EXPECT_EQ(std::memcmp(&t, &serial, sizeof t), 0) << "threads " << threads << ": " << t << " vs " << serial;
    }
  }
}

TEST(WorkerPool, FirstExceptionReachesTheCallerAndThePoolStaysUsable) {
  for (int threads : {1, 3}) {
    WorkerPool pool(threads);
    std::atomic<int> ran{0};
    EXPECT_THROW(pool.forBlocks(50,
                                [&](std::size_t b) {
                                  ++ran;
                                  if (b == 17) throw std::runtime_error("block 17");
                                }),
                 std::runtime_error);
    EXPECT_EQ(ran.load(), 50) << "the other blocks still run";
    std::atomic<int> after{0};
    pool.forBlocks(20, [&](std::size_t) { ++after; });
    EXPECT_EQ(after.load(), 20);
  }
}

TEST(WorkerPool, RefusesBadThreadCounts) {
  EXPECT_THROW(WorkerPool(0), std::invalid_argument);
  EXPECT_THROW(WorkerPool(-2), std::invalid_argument);
  EXPECT_THROW(WorkerPool(WorkerPool::kMaxThreads + 1), std::invalid_argument);
  const int d = defaultThreadCount();
  EXPECT_GE(d, 1);
  EXPECT_LE(d, 4);
}
