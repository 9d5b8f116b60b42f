// The long-term visual map on revisits (config/sim/revisit.yaml: a small block driven three times with
// the map scaled down, so that each lap leaves the start area for longer than the local cube holds it):
// with the long-term map the error is lower than without it (map.longterm_enabled false), at the
// same selection of images. Oracle: the simulator's ground truth.
// livo-test-long: 900
// livo-test-deps: livo_sim livo_estimation livo_eval
#include "pipeline_test_util.hpp"

#include <gtest/gtest.h>

using namespace livo;
using livo_test::RunSummary;
using livo_test::runScenario;
using livo_test::scenarioPath;

TEST(PipelineRevisit, LongtermVisualMapLowersTheErrorOnRevisits) {
  const sim::SimScenario sc = sim::loadScenarioFile(scenarioPath("revisit"));
  ASSERT_GT(sc.rig_map.local_edge_m, 0.0) << "the scenario scales the map down";
  const RunSummary with = runScenario(sc, 0.0, "adaptive");
  const RunSummary without =
      runScenario(sc, 0.0, "adaptive", {}, 1, [](PipelineConfig& cfg) { cfg.map.longterm_enabled = false; });
  ASSERT_GT(with.eval.path_length_m, 800.0) << "three laps";
  ASSERT_EQ(with.est.size(), without.est.size());
  // Measured 2026-12-02 (scripts/bench --ablation longterm, after the long-term points' cell
  // preference): 1.70 cm with, 2.85 cm without (0.60x); the bound is about twice the figure with, and
  // with must stay clearly below without (at least 30 % lower).
  EXPECT_LE(with.eval.ate.translation_m.rmse, 0.034);
  EXPECT_LE(with.eval.ate.translation_m.rmse, 0.8 * without.eval.ate.translation_m.rmse);
  EXPECT_GT(with.visual_frames, 300u);
}
