// The run's output files (libs/io RunOutputs): which frames the timing statistics of stats.json and
// the end-of-run summary cover (the frames after initialisation; the visual update's cost per image
// over the frames that ran it), against statistics computed by hand for known per-frame times.
#include "livo/io/run_outputs.hpp"

#include "process_test_files.hpp"

#include <gtest/gtest.h>

#include "livo/eval/tum.hpp"

#include <fstream>
#include <regex>
#include <string>

using namespace livo;
using test::readFile;

namespace {

/// The {mean, median, p95, max, count} object of timing_ms.<name> in stats.json, as text.
std::string timing(const std::string& stats, const std::string& name) {
  const std::regex re("\"" + name + "\": (\\{[^}]*\\})");
  std::smatch m;
  if (!std::regex_search(stats, m, re)) return "<" + name + " missing>";
  return m[1];
}

FrameRecord frame(Utime t, bool pose, double lio, double vio, bool visual) {
  FrameRecord r;
  r.utime = t;
  r.has_pose = pose;
  r.lio_ms = lio;
  r.vio_ms = vio;
  r.map_ms = 1.0;
  r.total_ms = lio + vio + 1.0;
  r.visual_used = visual;
  return r;
}

}  // namespace

TEST(RunOutputs, TimingCoversTheFramesAfterInitialisation) {
  const std::string dir = test::tempDir("run_outputs_timing");
  {
    RunOutputs out(dir);
    // Three frames while the IMU initialises (no pose, ~0 ms), then five estimated frames of which
    // two ran the visual update (100 and 300 ms).
    for (int i = 0; i < 3; ++i) out.addFrame(frame(1000000 + i * 100000, false, 0.01, 0.0, false));
    const double lio[5] = {10, 20, 30, 40, 50};
    const double vio[5] = {0, 100, 0, 300, 0};
    for (int i = 0; i < 5; ++i) out.addFrame(frame(2000000 + i * 100000, true, lio[i], vio[i], vio[i] > 0));
    out.writeStats(MapSummary{}, 12.5);
    const std::string summary = out.summary(12.5);
    EXPECT_NE(summary.find("times over the 5 frames after initialisation"), std::string::npos) << summary;
    EXPECT_NE(summary.find("visual update per visual frame [ms]  mean 200.00 median 200.00 p95 300.00 max 300.00 (2 frames)"),
              std::string::npos)
        << summary;
  }
  const std::string stats = test::readFile(dir + "/stats.json");
  EXPECT_NE(stats.find("\"frames\": 8"), std::string::npos) << stats;
  EXPECT_NE(stats.find("\"timed_frames\": 5"), std::string::npos) << stats;
  EXPECT_NE(stats.find("\"visual_frames\": 2"), std::string::npos) << stats;
  // By hand: lio {10..50} -> mean 30, median 30, p95 (rank ceil(0.95*5) = 5) 50.
  EXPECT_EQ(timing(stats, "lio"), "{\"mean\": 30, \"median\": 30, \"p95\": 50, \"max\": 50, \"count\": 5}");
  // vio over every timed frame, zeros included: mean 80, median 0.
  EXPECT_EQ(timing(stats, "vio"), "{\"mean\": 80, \"median\": 0, \"p95\": 300, \"max\": 300, \"count\": 5}");
  // The cost of one image: the two frames that ran it.
  EXPECT_EQ(timing(stats, "vio_per_visual_frame"),
            "{\"mean\": 200, \"median\": 200, \"p95\": 300, \"max\": 300, \"count\": 2}");
  // total = lio + vio + 1 over the five: {11, 121, 31, 341, 51} -> mean 111, median 51.
  EXPECT_EQ(timing(stats, "total"), "{\"mean\": 111, \"median\": 51, \"p95\": 341, \"max\": 341, \"count\": 5}");
}

TEST(RunOutputs, NoVisualFrameGivesNullPerImageStatistics) {
  const std::string dir = test::tempDir("run_outputs_novisual");
  {
    RunOutputs out(dir);
    for (int i = 0; i < 4; ++i) out.addFrame(frame(1000000 + i * 100000, true, 5.0, 0.0, false));
    out.writeStats(MapSummary{}, 1.0);
  }
  const std::string stats = test::readFile(dir + "/stats.json");
  EXPECT_EQ(timing(stats, "vio_per_visual_frame"),
            "{\"mean\": null, \"median\": null, \"p95\": null, \"max\": null, \"count\": 0}");
  EXPECT_EQ(timing(stats, "vio"), "{\"mean\": 0, \"median\": 0, \"p95\": 0, \"max\": 0, \"count\": 4}");
}

TEST(RunOutputs, AppendModeContinuesFilesCutByAKillAndKeepsTimeIncreasing) {
  const std::string dir = test::tempDir("run_outputs_append");
  {
    RunOutputs first(dir, /*append=*/true);  // nothing there yet: a new file with its header
    for (int i = 1; i <= 3; ++i) first.addFrame(frame(i * 100000, true, 2, 0, false));
  }
  // A kill in the middle of writing a line of each file.
  { std::ofstream(dir + "/trajectory.tum", std::ios::app) << "0.4 1.0 2.0"; }
  { std::ofstream(dir + "/frames.csv", std::ios::app) << "0.400000,3.1"; }
  {
    RunOutputs second(dir, /*append=*/true);
    EXPECT_EQ(second.previousPoses(), 3u);
    EXPECT_DOUBLE_EQ(second.lastPoseTime(), 0.3);
    // Frames the first writer wrote already (a replay overlap) are left out; later ones follow.
    second.addFrame(frame(200000, true, 2, 0, false));
    second.addFrame(frame(300000, true, 2, 0, false));
    second.addFrame(frame(500000, true, 2, 0, false));
    second.addFrame(frame(600000, false, 2, 0, false));
    EXPECT_EQ(second.skippedFrames(), 2u);
    EXPECT_EQ(second.frames(), 2u);
    EXPECT_EQ(second.posesWritten(), 1u);
  }
  const Trajectory t = readTum(dir + "/trajectory.tum");  // throws on a partial or non-increasing line
  ASSERT_EQ(t.size(), 4u);
  EXPECT_DOUBLE_EQ(t.back().t, 0.5);
  const std::vector<std::string> rows = test::lines(readFile(dir + "/frames.csv"));
  ASSERT_EQ(rows.size(), 1u + 3 + 2) << "one header, three rows, two rows";
  EXPECT_EQ(rows[0].rfind("t,lio_ms", 0), 0u);
  EXPECT_EQ(rows[4].rfind("0.500000,", 0), 0u) << rows[4];
  EXPECT_EQ(rows[5].rfind("0.600000,", 0), 0u) << rows[5];
  for (const std::string& r : rows) EXPECT_EQ(r.find("0.400000,3.1"), std::string::npos) << "the cut row is gone";

  // Without append mode the files start again.
  { RunOutputs fresh(dir); }
  EXPECT_EQ(test::lines(readFile(dir + "/frames.csv")).size(), 1u);
}
