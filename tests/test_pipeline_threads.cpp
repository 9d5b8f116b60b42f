// --threads: the per-frame loops (LiDAR association, photometric patches) run on a worker pool in
// fixed blocks summed in block order, so a run gives the same trajectory to the bit for every thread
// count. Oracle: the one-thread run of the same simulated log, pose by pose.
// livo-test-deps: livo_sim livo_estimation livo_eval
#include "pipeline_test_util.hpp"

#include <gtest/gtest.h>

#include <cstring>

using namespace livo;
using livo_test::RunSummary;
using livo_test::runScenario;
using livo_test::scenarioPath;

namespace {

/// Number of poses of `b` that differ from `a` in any bit (and the first one's index).
std::size_t differingPoses(const RunSummary& a, const RunSummary& b, std::size_t& first) {
  std::size_t n = 0;
  first = a.est.size();
  for (std::size_t i = 0; i < a.est.size() && i < b.est.size(); ++i) {
    const Eigen::Matrix4d& A = a.est[i].T_world_body.matrix();
    const Eigen::Matrix4d& B = b.est[i].T_world_body.matrix();
    if (a.est[i].t != b.est[i].t || std::memcmp(A.data(), B.data(), sizeof(double) * 16) != 0) {
      if (n == 0) first = i;
      ++n;
    }
  }
  return n;
}

void expectSameForEveryThreadCount(const std::string& scenario, double duration_s, const std::string& mode) {
  const sim::SimScenario sc = sim::loadScenarioFile(scenarioPath(scenario));
  const RunSummary one = runScenario(sc, duration_s, mode, {}, 1);
  ASSERT_GT(one.est.size(), 40u);
  if (mode != "off") {
    ASSERT_GT(one.visual_frames, 20u) << "the visual update must be exercised";
  }
  for (int threads : {2, 3}) {
    const RunSummary many = runScenario(sc, duration_s, mode, {}, threads);
    ASSERT_EQ(many.est.size(), one.est.size()) << threads << " threads";
    std::size_t first = 0;
    EXPECT_EQ(differingPoses(one, many, first), 0u)
        << scenario << " " << mode << ", " << threads << " threads: first differing pose " << first;
    EXPECT_EQ(many.visual_frames, one.visual_frames);
    EXPECT_EQ(many.degenerate_frames, one.degenerate_frames);
  }
}

}  // namespace

TEST(PipelineThreads, RoomAllImagesSameTrajectoryForEveryThreadCount) {
  expectSameForEveryThreadCount("room", 6.0, "all");
}

// The corridor is LiDAR-degenerate: the visual update carries the estimate, so a difference in its
// per-point sums would show at once.
TEST(PipelineThreads, CorridorAdaptiveSameTrajectoryForEveryThreadCount) {
  expectSameForEveryThreadCount("corridor", 8.0, "adaptive");
}

TEST(PipelineThreads, BadThreadCountIsRefused) {
  PipelineConfig cfg;
  cfg.threads = 0;
  EXPECT_THROW(FramePipeline{cfg}, std::invalid_argument);
  cfg.threads = WorkerPool::kMaxThreads + 1;
  EXPECT_THROW(FramePipeline{cfg}, std::invalid_argument);
}
