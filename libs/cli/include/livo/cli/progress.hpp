// The progress line of the long commands (livo-sim, livo-run, livo-convert): one line on stderr,
// rewritten in place, with the percentage done, a count and its rate, and the time left:
//
//   livo-run:  42.3% | 812 frames, 96.1 frames/s | 0:08 elapsed, 0:11 left
//
// Shown when stderr is a terminal, or always with --progress (then also into a pipe or file, for a
// script that shows it: scripts/bench); never with --quiet. The time left is the elapsed time scaled
// by the part still to do (elapsed * (1 - f) / f): the mean rate so far, no smoothing to tune.
//
//   ProgressLine progress("livo-run", "frames", progressMode(args.progress, args.quiet));
//   while (...) progress.update(fraction_done, frames);
//   progress.finish();
#pragma once

#include <cstdio>
#include <functional>
#include <string>

namespace livo {

class CommandLine;

/// When the line is drawn.
enum class ProgressMode {
  kTerminal,  ///< only when the stream is a terminal (the default)
  kAlways,    ///< --progress: also into a pipe or file
  kNever,     ///< --quiet
};

/// The mode for --progress and --quiet (--quiet wins).
ProgressMode progressMode(bool progress_flag, bool quiet);

/// Registers --progress (a flag) on `cl`.
void addProgressOption(CommandLine& cl, bool* progress_flag);

/// "0:08", "12:34", "1:02:03" (to the nearest second; negative or non-finite as "--:--").
std::string formatDuration(double seconds);

/// The text of one progress line (no '\r'): `program`, the percentage of `fraction` (clamped to
/// [0, 1]), `count` `unit` with their rate over `elapsed_s`, the elapsed time and the time left (shown
/// once at least 0.1 % is done and 0.5 s have passed; "--:--" before).
std::string formatProgress(const std::string& program, double fraction, double count, const std::string& unit,
                           double elapsed_s);

class ProgressLine {
 public:
  /// Seconds on a monotonic clock; the default is std::chrono::steady_clock. Tests pass their own.
  using Clock = std::function<double()>;

  /// Draws on `out` (stderr by default); kTerminal checks isatty() of `out`'s descriptor once here.
  /// `min_interval_s`: redraws at most this often (the first update and finish() always draw).
  ProgressLine(std::string program, std::string unit, ProgressMode mode, std::FILE* out = stderr,
               Clock clock = {}, double min_interval_s = 0.25);
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  /// Whether anything is drawn.
  bool enabled() const { return enabled_; }
  /// `fraction` of the work done (0..1) and `count` units so far (frames, messages, images).
  void update(double fraction, double count);
  /// Draws the last state once more and ends the line ('\n'); later calls do nothing. Nothing is
  /// printed when nothing was drawn before.
  void finish();
  /// Prints `line` (and '\n') on the stream as a line of its own: the progress line is blanked first
  /// and drawn again below it. Without a drawn line (disabled, not yet drawn, finished) just the line.
  void message(const std::string& line);

 private:
  void draw(double now);

  std::string program_, unit_;
  bool enabled_ = false, finished_ = false, drawn_ = false;
  std::FILE* out_;
  Clock clock_;
  double min_interval_s_, start_ = 0.0, last_draw_ = 0.0;
  double fraction_ = 0.0, count_ = 0.0;
  std::size_t last_width_ = 0;
};

}  // namespace livo
