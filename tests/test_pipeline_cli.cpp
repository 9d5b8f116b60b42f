// livo-run as users run it: livo-sim writes a short demo log and its rig, livo-run processes it in each
// visual mode, and the output directory holds every file of the contract with the documented fields.
// livo-test-bins: livo-sim livo-run livo-eval
#include "pipeline_cli_test_util.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using livo::test::bin;
using livo::test::run;
using livo::test::slurp;

TEST(LivoRun, WritesEveryOutputFileInEachVisualMode) {
  for (const char* b : {"livo-sim", "livo-run", "livo-eval"})
    if (!fs::exists(bin(b))) LIVO_SKIP() << bin(b) << " not built";
  const fs::path dir = fs::temp_directory_path() / ("livo_test_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string log = (dir / "demo.lcm").string(), gt = (dir / "gt.tum").string(), rig = (dir / "rig.yaml").string();
  ASSERT_EQ(run(bin("livo-sim") + " --scenario " + LIVO_SOURCE_DIR + "/config/sim/demo.yaml --out " + log + " --gt " + gt +
                " --rig " + rig + " --duration 8 --quiet"),
            0);
  for (const std::string mode : {"off", "adaptive", "all"}) {
    SCOPED_TRACE(mode);
    const fs::path out = dir / ("out_" + mode);
    ASSERT_EQ(run(bin("livo-run") + " " + log + " --config " + rig + " --out " + out.string() + " --visual-mode " + mode +
                  " --quiet"),
              0);
    for (const char* f : {"trajectory.tum", "frames.csv", "stats.json", "map.pcd", "map.bt"})
      EXPECT_TRUE(fs::exists(out / f)) << f;
    const std::string csv = slurp(out / "frames.csv");
    EXPECT_EQ(csv.substr(0, csv.find('\n')),
              "t,lio_ms,vio_ms,total_ms,sigma_min,degenerate,visual_used,n_points,n_planes_matched,n_visual_points,"
              "map_bytes");
    const std::vector<double> map_bytes = livo::test::csvColumn(out / "frames.csv", "map_bytes");
    ASSERT_FALSE(map_bytes.empty());
    EXPECT_GT(map_bytes.back(), 0.0);  // the map's bytes after the last frame
    const std::string stats = slurp(out / "stats.json");
    for (const char* key : {"\"frames\"", "\"visual_frames\"", "\"degenerate_frames\"", "\"timing_ms\"", "\"lio\"",
                            "\"vio\"", "\"map\"", "\"total\"", "\"median\"", "\"p95\"", "\"peak_rss_mb\"",
                            "\"local_voxels\"", "\"visual_points_local\"", "\"visual_points_longterm\"", "\"bytes\""})
      EXPECT_NE(stats.find(key), std::string::npos) << key;
    EXPECT_EQ(stats.find("\"visual_frames\": 0,") != std::string::npos, mode == "off") << stats.substr(0, 200);
    const std::string pcd = slurp(out / "map.pcd");
    EXPECT_NE(pcd.find("FIELDS x y z rgb"), std::string::npos);
    EXPECT_EQ(slurp(out / "map.bt").rfind("# Octomap OcTree binary file", 0), 0u);
    EXPECT_EQ(run(bin("livo-eval") + " --gt " + gt + " --est " + (out / "trajectory.tum").string()), 0);
  }
  // A bad config key and a missing log fail with a non-zero exit, never a crash.
  std::ofstream(dir / "bad.yaml") << slurp(rig) << "lio:\n  max_iteratons: 3\n";
  EXPECT_NE(run(bin("livo-run") + " " + log + " --config " + (dir / "bad.yaml").string() + " --out " + (dir / "x").string()), 0);
  EXPECT_NE(run(bin("livo-run") + " " + (dir / "missing.lcm").string() + " --config " + rig + " --out " + (dir / "y").string()), 0);
  fs::remove_all(dir);
}
