// libs/eval: time association of estimate and ground truth against a brute-force oracle (max dt, time
// offset, one-to-one when the estimate is faster).
#include "eval_test_util.hpp"

#include "livo/eval/evaluate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace livo;
using namespace livo::test;

namespace {

// Brute force: every estimated pose against every ground-truth pose; nearest (last on ties), then
// one-to-one (closest, first on ties).
std::vector<PosePair> bruteForceAssociate(const Trajectory& gt, const Trajectory& est, double max_dt,
                                          double offset) {
  std::vector<PosePair> candidates;
  std::vector<double> dts;
  for (std::size_t e = 0; e < est.size(); ++e) {
    std::size_t best = 0;
    for (std::size_t g = 0; g < gt.size(); ++g)
      if (std::abs(gt[g].t - (est[e].t + offset)) <= std::abs(gt[best].t - (est[e].t + offset))) best = g;
    const double dt = std::abs(gt[best].t - (est[e].t + offset));
    if (dt <= max_dt) {
      candidates.push_back({best, e});
      dts.push_back(dt);
    }
  }
  std::vector<PosePair> out;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    bool keep = true;
    for (std::size_t m = 0; m < candidates.size(); ++m) {
      if (m == k || candidates[m].gt_index != candidates[k].gt_index) continue;
      if (dts[m] < dts[k] || (dts[m] == dts[k] && m < k)) keep = false;
    }
    if (keep) out.push_back(candidates[k]);
  }
  return out;
}

Trajectory timesOnly(const std::vector<double>& times) {
  Trajectory traj;
  for (double t : times) traj.push_back({t, Pose::Identity()});
  return traj;
}

}  // namespace

// ---------------------------------------------------------------- association

TEST(Associate, MatchesBruteForceOnRandomTimes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 30; ++trial) {
    // Ground truth ~20 Hz with jitter; estimate at a random rate with random gaps and a random shift.
    std::vector<double> tg, te;
    for (double t = 0; t < 20; t += 0.03 + 0.04 * u(rng)) tg.push_back(t);
    const double step = 0.005 + 0.1 * u(rng);
    for (double t = -2 + 4 * u(rng); t < 22; t += step * (0.5 + u(rng)))
      if (u(rng) > 0.2) te.push_back(t);
    const double max_dt = 0.002 + 0.03 * u(rng);
    const double offset = 0.05 * (u(rng) - 0.5);
    const auto fast = associate(timesOnly(tg), timesOnly(te), max_dt, offset);
    const auto slow = bruteForceAssociate(timesOnly(tg), timesOnly(te), max_dt, offset);
    ASSERT_EQ(fast.size(), slow.size()) << "trial " << trial;
    for (std::size_t k = 0; k < fast.size(); ++k) {
      EXPECT_EQ(fast[k].gt_index, slow[k].gt_index) << "trial " << trial << " pair " << k;
      EXPECT_EQ(fast[k].est_index, slow[k].est_index) << "trial " << trial << " pair " << k;
    }
  }
}

TEST(Associate, MaxDtAndTimeOffset) {
  std::vector<double> tg, te_close, te_far;
  for (int k = 0; k < 100; ++k) {
    tg.push_back(10.0 + 0.05 * k);
    te_close.push_back(10.0 + 0.05 * k + 0.008);
    te_far.push_back(10.0 + 0.05 * k + 0.023);  // 23 ms after one gt pose, 27 ms before the next
  }
  EXPECT_EQ(associate(timesOnly(tg), timesOnly(te_close), 0.01).size(), 100u);
  EXPECT_EQ(associate(timesOnly(tg), timesOnly(te_close), 0.005).size(), 0u);
  EXPECT_EQ(associate(timesOnly(tg), timesOnly(te_far), 0.01).size(), 0u);
  const auto shifted = associate(timesOnly(tg), timesOnly(te_far), 0.01, -0.023);
  ASSERT_EQ(shifted.size(), 100u);
  for (std::size_t k = 0; k < shifted.size(); ++k) EXPECT_EQ(shifted[k].gt_index, shifted[k].est_index);
}

TEST(Associate, FasterEstimateIsMatchedOneToOne) {
  std::vector<double> tg, te;
  for (int k = 0; k < 50; ++k) tg.push_back(0.05 * k);
  for (int k = 0; k < 250; ++k) te.push_back(0.01 * k + 0.001);  // 100 Hz, every 5th within 1 ms
  const auto pairs = associate(timesOnly(tg), timesOnly(te), 0.01);
  ASSERT_EQ(pairs.size(), 50u);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    EXPECT_EQ(pairs[k].gt_index, k);
    EXPECT_EQ(pairs[k].est_index, 5 * k);
  }
}
