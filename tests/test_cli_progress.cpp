// The progress line of the long commands (libs/cli progress.hpp): the text (percent, count and rate,
// elapsed and time left) on a clock the test sets, when it is drawn (terminal, --progress, --quiet),
// how often, and that finish() ends the line once; livo-sim, livo-run and livo-convert draw it into a
// file with --progress and never without (a file is no terminal).
// livo-test-bins: livo-sim livo-run livo-convert
#include "livo/cli/progress.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>
#include <unistd.h>

using livo::formatDuration;
using livo::formatProgress;
using livo::ProgressLine;
using livo::ProgressMode;

namespace {

/// What a ProgressLine wrote into a temporary file.
std::string contents(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  for (int c; (c = std::fgetc(f)) != EOF;) s += static_cast<char>(c);
  return s;
}

}  // namespace

TEST(Progress, DurationsReadAsClockTimes) {
  EXPECT_EQ(formatDuration(0.0), "0:00");
  EXPECT_EQ(formatDuration(8.9), "0:09");
  EXPECT_EQ(formatDuration(11.9999), "0:12");
  EXPECT_EQ(formatDuration(754.0), "12:34");
  EXPECT_EQ(formatDuration(3723.0), "1:02:03");
  EXPECT_EQ(formatDuration(-1.0), "--:--");
  EXPECT_EQ(formatDuration(1.0 / 0.0), "--:--");
}

TEST(Progress, LineHasPercentRateAndTimeLeft) {
  // 40 % in 8 s: the remaining 60 % at the same mean rate take 12 s; 200 frames in 8 s = 25 frames/s.
  EXPECT_EQ(formatProgress("livo-run", 0.4, 200, "frames", 8.0),
            "livo-run:  40.0% | 200 frames, 25.0 frames/s | 0:08 elapsed, 0:12 left");
  EXPECT_EQ(formatProgress("livo-sim", 1.0, 45000, "messages", 90.0),
            "livo-sim: 100.0% | 45000 messages, 500 messages/s | 1:30 elapsed, 0:00 left");
  // Too early to tell: nothing done yet, or under half a second.
  EXPECT_EQ(formatProgress("x", 0.0, 0, "scans", 3.0), "x:   0.0% | 0 scans, 0.0 scans/s | 0:03 elapsed, --:-- left");
  EXPECT_EQ(formatProgress("x", 0.5, 1, "scans", 0.2), "x:  50.0% | 1 scans, 5.0 scans/s | 0:00 elapsed, --:-- left");
  EXPECT_EQ(formatProgress("x", 2.0, 3, "scans", 0.0), "x: 100.0% | 3 scans, - scans/s | 0:00 elapsed, 0:00 left");
}

TEST(Progress, DrawsInPlaceAtMostEveryIntervalAndEndsTheLineOnce) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  double now = 0.0;  // binary fractions below: exact sums
  {
    ProgressLine p("livo-x", "events", ProgressMode::kAlways, f, [&] { return now; }, 0.25);
    ASSERT_TRUE(p.enabled());
    p.update(0.1, 10);  // drawn (first)
    now += 0.125;
    p.update(0.2, 20);  // too soon: not drawn
    now += 0.25;
    p.update(0.3, 30);  // drawn
    p.finish();         // drawn again and ended
    p.finish();
    p.update(0.9, 90);  // after finish: nothing
  }
  const std::string out = contents(f);
  std::fclose(f);
  EXPECT_EQ(out,
            "\rlivo-x:  10.0% | 10 events, - events/s | 0:00 elapsed, --:-- left"
            "\rlivo-x:  30.0% | 30 events, 80.0 events/s | 0:00 elapsed, --:-- left"
            "\rlivo-x:  30.0% | 30 events, 80.0 events/s | 0:00 elapsed, --:-- left\n");
}

TEST(Progress, ShorterLinesBlankTheRestOfTheLongerOne) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  double now = 0.0;
  ProgressLine p("x", "s", ProgressMode::kAlways, f, [&] { return now; }, 0.0);
  now = 1.0;
  p.update(0.5, 1234.4);
  now = 2.0;
  p.update(0.6, 1);
  const std::string out = contents(f);
  p.finish();  // before the file goes (the destructor would draw into it)
  std::fclose(f);
  const std::string first = "x:  50.0% | 1234.4 s, 1234 s/s | 0:01 elapsed, 0:01 left";
  const std::string second = "x:  60.0% | 1 s, 0.5 s/s | 0:02 elapsed, 0:01 left";
  EXPECT_EQ(out, "\r" + first + "\r" + second + std::string(first.size() - second.size(), ' '));
}

TEST(Progress, MessagesGoAboveTheLine) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  double now = 0.0;
  ProgressLine p("x", "s", ProgressMode::kAlways, f, [&] { return now; }, 10.0);
  p.message("before any line");
  p.update(0.5, 1);
  p.message("x: something happened");
  p.finish();
  p.message("after");
  const std::string out = contents(f);
  std::fclose(f);
  const std::string line = "x:  50.0% | 1 s, - s/s | 0:00 elapsed, --:-- left";
  EXPECT_EQ(out, "before any line\n\r" + line + "\r" + std::string(line.size(), ' ') + "\rx: something happened\n\r" +
                     line + "\r" + line + "\nafter\n");
}

TEST(Progress, SilentWhenNotATerminalUnlessAskedAndAlwaysWithQuiet) {
  EXPECT_EQ(livo::progressMode(false, false), ProgressMode::kTerminal);
  EXPECT_EQ(livo::progressMode(true, false), ProgressMode::kAlways);
  EXPECT_EQ(livo::progressMode(true, true), ProgressMode::kNever);
  for (const ProgressMode mode : {ProgressMode::kTerminal, ProgressMode::kNever}) {
    std::FILE* f = std::tmpfile();  // a file is no terminal
    ASSERT_NE(f, nullptr);
    {
      ProgressLine p("x", "s", mode, f);
      EXPECT_FALSE(p.enabled());
      p.update(0.5, 1);
      p.finish();
    }
    EXPECT_EQ(contents(f), "");
    ProgressLine q("x", "s", mode, f);
    q.message("messages still print");
    EXPECT_EQ(contents(f), "messages still print\n");
    std::fclose(f);
  }
}

namespace {

const std::string kBin = std::string(LIVO_BINARY_DIR) + "/bin";

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Runs `cmd` with stderr into `err` (a file: not a terminal); returns the exit code.
int runWithStderr(const std::string& cmd, const std::string& err) {
  const int rc = std::system((cmd + " > /dev/null 2> " + err).c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// The last drawing of the progress line in `text` (what follows the last '\r').
std::string lastDrawing(const std::string& text, const std::string& program) {
  const auto at = text.rfind("\r" + program + ": ");
  if (at == std::string::npos) return "";
  return text.substr(at + 1, text.find('\n', at) - at - 1);
}

}  // namespace

TEST(ProgressOfTheBinaries, DrawnIntoFilesWithProgressOnlyAndReachingTheEnd) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("livo_progress_" + std::to_string(::getpid()));
  fs::create_directories(dir / "kitti");
  const std::string d = dir.string();
  const std::string sim = kBin + "/livo-sim --scenario " + std::string(LIVO_SOURCE_DIR) + "/config/sim/demo.yaml --out " +
                          d + "/log.lcm --gt " + d + "/gt.tum --rig " + d + "/rig.yaml --duration 1.5";
  ASSERT_EQ(runWithStderr(sim, d + "/sim_quiet.txt"), 0) << slurp(d + "/sim_quiet.txt");
  EXPECT_EQ(slurp(d + "/sim_quiet.txt").find("% | "), std::string::npos) << "no progress line into a file without --progress";
  ASSERT_EQ(runWithStderr(sim + " --progress", d + "/sim.txt"), 0) << slurp(d + "/sim.txt");
  const std::string s = lastDrawing(slurp(d + "/sim.txt"), "livo-sim");
  EXPECT_EQ(s.rfind("livo-sim: 100.0% | ", 0), 0u) << slurp(d + "/sim.txt");
  EXPECT_NE(s.find(" messages/s | "), std::string::npos) << s;
  EXPECT_NE(s.find(" left"), std::string::npos) << s;
  ASSERT_EQ(runWithStderr(sim + " --progress --quiet", d + "/sim_q.txt"), 0);
  EXPECT_EQ(slurp(d + "/sim_q.txt"), "") << "--quiet wins";

  const std::string run = kBin + "/livo-run " + d + "/log.lcm --config " + d + "/rig.yaml --out " + d + "/out";
  ASSERT_EQ(runWithStderr(run, d + "/run_quiet.txt"), 0) << slurp(d + "/run_quiet.txt");
  EXPECT_EQ(slurp(d + "/run_quiet.txt").find("% | "), std::string::npos) << slurp(d + "/run_quiet.txt");
  ASSERT_EQ(runWithStderr(run + " --progress", d + "/run.txt"), 0) << slurp(d + "/run.txt");
  const std::string r = lastDrawing(slurp(d + "/run.txt"), "livo-run");
  EXPECT_EQ(r.rfind("livo-run: 100.0% | ", 0), 0u) << slurp(d + "/run.txt");
  EXPECT_NE(r.find(" frames/s | "), std::string::npos) << r;
  // Messages while the line is drawn get lines of their own (the initialisation message): the line is
  // blanked, the message printed and ended, the line drawn again.
  const std::string all = slurp(d + "/run.txt");
  const auto init = all.find("\rlivo-run: filter started from");
  ASSERT_NE(init, std::string::npos) << all;
  EXPECT_EQ(all.substr(all.find('\n', init) + 1, 11), "\rlivo-run: ") << all;

  // livo-convert kitti: three scans of two float32 x y z intensity points.
  for (int i = 0; i < 3; ++i) {
    std::ofstream f(dir / "kitti" / ("00000" + std::to_string(i) + ".bin"), std::ios::binary);
    const float pts[8] = {1, 2, 3, 0.5f, 4, 5, 6, 0.25f};
    f.write(reinterpret_cast<const char*>(pts), sizeof pts);
  }
  const std::string conv = kBin + "/livo-convert kitti " + d + "/kitti --out " + d + "/k.lcm --rate-hz 10";
  ASSERT_EQ(runWithStderr(conv, d + "/conv_quiet.txt"), 0) << slurp(d + "/conv_quiet.txt");
  EXPECT_EQ(slurp(d + "/conv_quiet.txt").find("% | "), std::string::npos) << slurp(d + "/conv_quiet.txt");
  ASSERT_EQ(runWithStderr(conv + " --progress", d + "/conv.txt"), 0) << slurp(d + "/conv.txt");
  EXPECT_EQ(lastDrawing(slurp(d + "/conv.txt"), "livo-convert").rfind("livo-convert: 100.0% | 3 scans, ", 0), 0u)
      << slurp(d + "/conv.txt");
  fs::remove_all(dir);
}
