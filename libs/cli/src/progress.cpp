#include "livo/cli/progress.hpp"

#include "livo/cli/command_line.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <unistd.h>

namespace livo {

namespace {

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// "812" for whole numbers, "12.5" otherwise; rates above 100 without decimals.
std::string formatCount(double v, bool is_rate) {
  char buf[64];
  if (!std::isfinite(v)) return "-";
  if ((!is_rate && v == std::floor(v)) || (is_rate && std::abs(v) >= 100.0))
    std::snprintf(buf, sizeof buf, "%.0f", v);
  else
    std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

}  // namespace

ProgressMode progressMode(bool progress_flag, bool quiet) {
  if (quiet) return ProgressMode::kNever;
  return progress_flag ? ProgressMode::kAlways : ProgressMode::kTerminal;
}

void addProgressOption(CommandLine& cl, bool* progress_flag) {
  cl.flag("--progress", progress_flag,
          "draw the progress line (percent, rate, time left) on stderr even when it is not a terminal "
          "(default: only on a terminal)");
}

std::string formatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) return "--:--";
  const long long s = std::llround(seconds);
  char buf[64];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%lld:%02lld:%02lld", s / 3600, (s / 60) % 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%lld:%02lld", s / 60, s % 60);
  return buf;
}

std::string formatProgress(const std::string& program, double fraction, double count, const std::string& unit,
                           double elapsed_s) {
  const double f = std::isfinite(fraction) ? std::clamp(fraction, 0.0, 1.0) : 0.0;
  const double elapsed = std::max(0.0, elapsed_s);
  const double rate = elapsed > 0.0 ? count / elapsed : 0.0;
  const bool can_tell = f >= 1e-3 && elapsed >= 0.5;
  const std::string left = f >= 1.0 ? "0:00" : can_tell ? formatDuration(elapsed * (1.0 - f) / f) : "--:--";
  char pct[32];
  std::snprintf(pct, sizeof pct, "%5.1f%%", 100.0 * f);
  return program + ": " + pct + " | " + formatCount(count, false) + " " + unit + ", " +
         (elapsed > 0.0 ? formatCount(rate, true) : std::string("-")) + " " + unit + "/s | " +
         formatDuration(elapsed) + " elapsed, " + left + " left";
}

ProgressLine::ProgressLine(std::string program, std::string unit, ProgressMode mode, std::FILE* out, Clock clock,
                           double min_interval_s)
    : program_(std::move(program)), unit_(std::move(unit)), out_(out),
      clock_(clock ? std::move(clock) : Clock(steadySeconds)), min_interval_s_(min_interval_s) {
  enabled_ = out_ != nullptr &&
             (mode == ProgressMode::kAlways || (mode == ProgressMode::kTerminal && ::isatty(::fileno(out_)) != 0));
  start_ = clock_();
}

ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::update(double fraction, double count) {
  if (!enabled_ || finished_) return;
  fraction_ = fraction;
  count_ = count;
  const double now = clock_();
  if (drawn_ && now - last_draw_ < min_interval_s_) return;
  draw(now);
}

void ProgressLine::finish() {
  if (finished_) return;
  finished_ = true;
  if (!enabled_ || !drawn_) return;
  draw(clock_());
  std::fputc('\n', out_);
  std::fflush(out_);
}

void ProgressLine::message(const std::string& line) {
  if (out_ == nullptr) return;
  const bool redraw = enabled_ && drawn_ && !finished_;
  if (redraw) std::fprintf(out_, "\r%*s\r", static_cast<int>(last_width_), "");
  std::fprintf(out_, "%s\n", line.c_str());
  if (redraw) {
    last_width_ = 0;
    draw(clock_());
  }
  std::fflush(out_);
}

void ProgressLine::draw(double now) {
  const std::string line = formatProgress(program_, fraction_, count_, unit_, now - start_);
  // Blanks over the rest of a longer previous line (no terminal escape codes: also fine in a file).
  const std::size_t pad = last_width_ > line.size() ? last_width_ - line.size() : 0;
  std::fprintf(out_, "\r%s%*s", line.c_str(), static_cast<int>(pad), "");
  std::fflush(out_);
  last_width_ = line.size();
  last_draw_ = now;
  drawn_ = true;
}

}  // namespace livo
