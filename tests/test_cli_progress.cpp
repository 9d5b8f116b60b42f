// The progress line of the long commands (libs/cli progress.hpp): the text (percent, count and rate,
// elapsed and time left) on a clock the test sets, when it is drawn (terminal, --progress, --quiet),
// how often, and that finish() ends the line once.
#include "livo/cli/progress.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

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
