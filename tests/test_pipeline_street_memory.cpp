// Issue #6 "Memory": config/sim/street.yaml (a 2.1 km loop of 700 x 360 m between buildings, spinning
// 32-ring LiDAR, seed 3) simulated once and run through livo-run three times, LiDAR-inertial
// (--visual-mode off, --no-maps: the map's bytes are the subject, not map.pcd / map.bt). The whole loop:
// the local map's level depends on the surroundings (corners vs straight streets), and over the first
// 1.1 km alone it went 61.2 -> 53.9 MiB (-12%, flat but outside the 10% band) where the loop gives
// 57.7 -> 57.5 MiB.
//   hybrid            the map's bytes (frames.csv map_bytes) level off: at the end within 10% of their
//                     level at one third of the frames;
//   global            one unbounded map: at the end more than 1.5 x its bytes at one third, and the hybrid
//                     map's final bytes (stats.json map.bytes) at most half the global map's;
//   hybrid, capped    map.memory_cap_mb 30 (in a copy of the rig config; the uncapped map holds ~58 MiB):
//                     map_bytes never above the cap in any frame, the final exact count under it;
// and every run's ATE RMSE stays under 0.1% of the path length (measured ~0.05 m / ~0.1 m capped on the
// full 2.1 km loop: hybrid 57.7 -> 57.5 MiB from one third to the end, global 317.5 -> 912.8 MiB).
//
// "Level": the median of map_bytes over one slide period (slides every 20 m at 10 m/s = 20 frames) around
// the frame: the local map saw-tooths by ~10% with each slide (its work is spread over frames), so two
// single frames could compare a peak with a trough.
// Why the visual update is off: with --visual-mode adaptive the 800 m long-term visual cube (map.
// longterm_edge_m) covers the whole 700 x 360 m loop, so long-term points are never dropped in one lap and
// the hybrid bytes grew 92 -> 112.5 MB (earlier measurement); that is the sparse long-term map doing its
// job, not unbounded local growth, but it fails the 10% criterion, and the visual update would also add
// minutes per run.
// Registered as ONE ctest test (the fixture shares the log and the runs) labelled `long`: `ctest -LE long`
// skips it. The temporary files (~1.8 GB) are removed at the end (kept when LIVO_KEEP_TEST_DIR is set).
// livo-test-long: 3600
// livo-test-bins: livo-sim livo-run
// livo-test-deps: livo_eval
#include "livo/eval/evaluate.hpp"
#include "pipeline_cli_test_util.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

using namespace livo;
using namespace livo::test;

namespace {

constexpr double kCapMiB = 30.0;
constexpr double kMiB = 1024.0 * 1024.0;
constexpr std::size_t kSlideFrames = 20;  // slide_distance_m 20 at 10 m/s and 10 frames/s

struct RunResult {
  std::vector<double> map_bytes;  ///< frames.csv, one per frame
  double stats_bytes = 0;         ///< stats.json map.bytes (exact count at the end)
  double eviction_events = 0;     ///< stats.json counters.map_eviction_events
  EvalResult eval;
};

// Median of v[first, last] (clamped to the series).
double medianOver(const std::vector<double>& v, std::size_t first, std::size_t last) {
  last = std::min(last, v.size() - 1);
  std::vector<double> w(v.begin() + std::ptrdiff_t(first), v.begin() + std::ptrdiff_t(last) + 1);
  std::nth_element(w.begin(), w.begin() + std::ptrdiff_t(w.size() / 2), w.end());
  return w[w.size() / 2];
}
// Level around the frame at one third of the run, and over the last slide period.
double levelAtThird(const std::vector<double>& v) {
  const std::size_t i = v.size() / 3;
  return medianOver(v, i - kSlideFrames / 2, i + kSlideFrames / 2);
}
double levelAtEnd(const std::vector<double>& v) { return medianOver(v, v.size() - 1 - kSlideFrames, v.size() - 1); }

class StreetMemory : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    for (const char* b : {"livo-sim", "livo-run"})
      if (!fs::exists(bin(b))) {
        skip_ = bin(b) + " not built";
        return;
      }
    dir_ = fs::temp_directory_path() / ("livo_test_street_memory_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    const std::string log = (dir_ / "street.lcm").string(), rig = (dir_ / "rig.yaml").string();
    gt_ = (dir_ / "gt.tum").string();
    if (run(bin("livo-sim") + " --scenario " + LIVO_SOURCE_DIR + "/config/sim/street.yaml --seed 3 --out " + log +
                " --gt " + gt_ + " --rig " + rig + " --quiet",
            (dir_ / "sim.log").string()) != 0) {
      error_ = "livo-sim failed:\n" + tail(dir_ / "sim.log");
      return;
    }
    const std::string rig_text = slurp(rig);
    if (rig_text.find("\nmap:") != std::string::npos) {
      error_ = "the simulated rig already has a map section; the capped config appends one";
      return;
    }
    const std::string capped = (dir_ / "rig_capped.yaml").string();
    std::ofstream(capped) << rig_text << "\nmap:\n  memory_cap_mb: " << kCapMiB << "\n";
    const std::vector<std::pair<std::string, std::string>> runs{
        {"hybrid", "--map-mode hybrid --config " + rig},
        {"global", "--map-mode global --config " + rig},
        {"capped", "--map-mode hybrid --config " + capped}};
    for (const auto& [name, args] : runs) {
      const fs::path out = dir_ / ("out_" + name);
      const std::string out_log = (dir_ / (name + ".log")).string();
      const std::string cmd = bin("livo-run") + " " + log + " " + args + " --visual-mode off --no-maps --quiet --out " + out.string();
      if (run(cmd, out_log) != 0) {
        error_ = "livo-run (" + name + ") failed:\n" + tail(out_log);
        return;
      }
      try {
        RunResult& r = runs_[name];
        r.map_bytes = csvColumn(out / "frames.csv", "map_bytes");
        const std::string stats = slurp(out / "stats.json");
        r.stats_bytes = jsonNumberAfter(stats, "\"local_voxels\"", "bytes");
        r.eviction_events = jsonNumberAfter(stats, "\"counters\"", "map_eviction_events");
        r.eval = evaluate(readTum(gt_), readTum((out / "trajectory.tum").string()), EvalConfig{});
      } catch (const std::exception& e) {
        error_ = name + ": " + e.what();
        return;
      }
    }
  }

  static void TearDownTestSuite() {
    if (dir_.empty() || std::getenv("LIVO_KEEP_TEST_DIR")) return;
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  void SetUp() override {
    if (!skip_.empty()) LIVO_SKIP() << skip_;
    ASSERT_TRUE(error_.empty()) << error_;
  }

  static const RunResult& result(const std::string& name) { return runs_.at(name); }

  static inline fs::path dir_;
  static inline std::string gt_, skip_, error_;
  static inline std::map<std::string, RunResult> runs_;
};

TEST_F(StreetMemory, HybridBytesLevelOff) {
  const std::vector<double>& b = result("hybrid").map_bytes;
  ASSERT_GT(b.size(), 2000u);  // ~2320 frames at 10 Hz
  const double third = levelAtThird(b), end = levelAtEnd(b);
  std::printf("hybrid map_bytes: %.1f MiB at 1/3 (frame %zu), %.1f MiB at the end (%zu frames), max %.1f MiB\n",
              third / kMiB, b.size() / 3, end / kMiB, b.size(), *std::max_element(b.begin(), b.end()) / kMiB);
  ASSERT_GT(third, 0.0);
  EXPECT_NEAR(end / third, 1.0, 0.10) << "third " << third << " end " << end;
}

TEST_F(StreetMemory, GlobalBytesKeepGrowing) {
  const std::vector<double>& b = result("global").map_bytes;
  ASSERT_GT(b.size(), 2000u);
  const double third = levelAtThird(b), end = levelAtEnd(b);
  std::printf("global map_bytes: %.1f MiB at 1/3, %.1f MiB at the end\n", third / kMiB, end / kMiB);
  ASSERT_GT(third, 0.0);
  EXPECT_GT(end, 1.5 * third) << "third " << third << " end " << end;
  EXPECT_EQ(b.size(), result("hybrid").map_bytes.size());  // the same frames
}

TEST_F(StreetMemory, HybridEndsAtMostHalfOfGlobal) {
  const double hybrid = result("hybrid").stats_bytes, global = result("global").stats_bytes;
  std::printf("stats.json map.bytes: hybrid %.1f MiB, global %.1f MiB (ratio %.3f)\n", hybrid / kMiB, global / kMiB,
              hybrid / global);
  EXPECT_GT(hybrid, 0.0);
  EXPECT_LE(hybrid, 0.5 * global);  // the claim
  // Measured 2026-12-06: 55.6 / 915.6 MiB = 0.061 (0.063 on 2026-12-04); about twice that.
  EXPECT_LE(hybrid, 0.12 * global);
}

TEST_F(StreetMemory, CappedHybridStaysUnderTheCapInEveryFrame) {
  const RunResult& r = result("capped");
  const double cap = kCapMiB * kMiB;
  // The cap binds: the uncapped map is bigger, and the capped run evicted.
  ASSERT_GT(levelAtEnd(result("hybrid").map_bytes), cap);
  EXPECT_GT(r.eviction_events, 0.0);
  ASSERT_EQ(r.map_bytes.size(), result("hybrid").map_bytes.size());
  const auto worst = std::max_element(r.map_bytes.begin(), r.map_bytes.end());
  std::printf("capped (%.0f MiB): max map_bytes %.2f MiB (frame %td), final exact %.2f MiB, %.0f eviction events\n",
              kCapMiB, *worst / kMiB, worst - r.map_bytes.begin(), r.stats_bytes / kMiB, r.eviction_events);
  for (std::size_t i = 0; i < r.map_bytes.size(); ++i)
    ASSERT_LE(r.map_bytes[i], cap) << "frame " << i;
  EXPECT_GT(r.stats_bytes, 0.0);
  EXPECT_LT(r.stats_bytes, cap);
}

TEST_F(StreetMemory, EveryRunTracksTheLoop) {
  // ATE over the 2102 m loop, measured 2026-12-07 with the one start (ef6c130): hybrid 17.1 cm, global
  // 17.1 cm, capped 6.3 cm (2026-12-06 with the start's rules: 5.0, 5.1 and 7.4 cm; why the uncapped runs
  // lost and the capped one gained is not examined yet: the start's attitude and velocity priors are
  // wider, the estimate the same). Bounds about twice those (0.1 % of the path, the claim, is 2.1 m).
  const std::map<std::string, double> bound{{"hybrid", 0.35}, {"global", 0.35}, {"capped", 0.15}};
  for (const char* name : {"hybrid", "global", "capped"}) {
    SCOPED_TRACE(name);
    const RunResult& r = result(name);
    std::printf("%s: ATE RMSE %.3f m over %.0f m (%.4f%%), %zu matched poses\n", name, r.eval.ate.translation_m.rmse,
                r.eval.path_length_m, 100.0 * r.eval.ate.translation_m.rmse / r.eval.path_length_m, r.eval.matched);
    EXPECT_GT(r.eval.path_length_m, 2000.0);
    EXPECT_GT(double(r.eval.matched), 0.98 * double(r.map_bytes.size()));
    EXPECT_LT(r.eval.ate.translation_m.rmse, 0.001 * r.eval.path_length_m);
    EXPECT_LT(r.eval.ate.translation_m.rmse, bound.at(name));
  }
}

}  // namespace
