#include "livo/io/run_outputs.hpp"

#include "livo/common/timing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace livo {

namespace {

std::string ensureDir(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create output directory: " + ec.message());
  return dir;
}

std::string jsonEscape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\', o += c;
    else if (static_cast<unsigned char>(c) < 0x20) o += ' ';
    else o += c;
  }
  return o;
}

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream os;
  os << std::setprecision(10) << v;
  return os.str();
}

/// {mean, median, p95, max, count}; with `null_when_empty` the statistics of no sample are null
/// (e.g. the visual update's time in a run without visual frames), else 0.
void writeSummary(std::ostream& os, const char* name, const SampleSummary& s, bool last, bool null_when_empty = false) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const bool none = null_when_empty && s.count == 0;
  os << "    \"" << name << "\": {\"mean\": " << num(none ? nan : s.mean) << ", \"median\": " << num(none ? nan : s.median)
     << ", \"p95\": " << num(none ? nan : s.p95) << ", \"max\": " << num(none ? nan : s.max) << ", \"count\": " << s.count
     << "}" << (last ? "\n" : ",\n");
}

}  // namespace

const char* frameState(const FrameRecord& f) {
  if (!f.has_pose) return healthName(HealthState::Initialising);
  if (f.health == HealthState::Ok && f.lidar_failed) return healthName(HealthState::Degraded);  // a record without the checks
  return healthName(f.health == HealthState::Initialising ? HealthState::Ok : f.health);
}

namespace {

/// The reason as one CSV field: no commas, quotes or line breaks.
std::string csvField(const std::string& s) {
  std::string o = s;
  for (char& c : o)
    if (c == ',' || c == '"' || c == '\n' || c == '\r') c = ';';
  return o;
}

}  // namespace

RunOutputs::RunOutputs(const std::string& dir, bool append)
    : dir_(ensureDir(dir)), append_(append), tum_(dir + "/trajectory.tum", append) {
  const std::string csv = dir + "/frames.csv";
  const ContinuedFile previous = append ? continueLineFile(csv) : ContinuedFile{};
  // Frames at or before the end of either file were written by the previous writer (a kill between
  // the two writes of a frame leaves its pose in trajectory.tum only).
  if (append) after_t_ = std::max(previous.last_t, tum_.lastTime());
  csv_.open(csv, previous.exists ? std::ios::out | std::ios::app : std::ios::out | std::ios::trunc);
  if (!csv_) throw std::runtime_error(csv + ": cannot open for writing");
  if (!previous.exists)
    csv_ << "t,lio_ms,vio_ms,total_ms,sigma_min,degenerate,visual_used,n_points,n_planes_matched,n_visual_points,"
            "map_bytes,n_longterm_points,time_offset_s,time_offset_sigma_s,state,reason\n";
  csv_.flush();
}

void RunOutputs::addFrame(const FrameRecord& f) {
  const double t = toSeconds(f.utime);
  if (append_) {
    if (!(t > after_t_)) {  // not after the files' end
      ++skipped_frames_;
      return;
    }
    after_t_ = t;
  }
  records_.push_back(f);
  records_.back().health_reason = std::string();  // written below, not kept
  if (f.has_pose) tum_.write(toSeconds(f.utime), f.T_world_imu);
  csv_ << std::fixed << std::setprecision(6) << toSeconds(f.utime) << std::setprecision(3) << ',' << f.lio_ms << ','
       << f.vio_ms << ',' << f.total_ms << ',' << std::setprecision(5) << f.sigma_min << ',' << int(f.degenerate)
       << ',' << int(f.visual_used) << ',' << f.n_points << ',' << f.n_planes_matched << ',' << f.n_visual_points
       << ',' << f.map_bytes << ',' << f.n_longterm_visual_points << ',';
  if (f.has_time_offset)
    csv_ << std::setprecision(7) << f.time_offset_s << ',' << f.time_offset_sigma_s;
  else
    csv_ << "nan,nan";
  csv_ << ',' << frameState(f) << ',' << csvField(f.health_reason) << '\n';
  csv_.flush();
  if (!csv_) throw std::runtime_error(dir_ + "/frames.csv: write failed");
}

namespace {

/// Per-frame times of the frames processed after initialisation (frames before it only fed the IMU
/// initialisation: ~0 ms each, they would pull every statistic down), and the visual update's time on
/// the frames that ran it (its cost per image).
struct FrameTimes {
  std::vector<double> lio, vio, map, map_wait, total, vio_per_visual_frame;
  std::size_t frames = 0, visual = 0, degenerate = 0;
  explicit FrameTimes(const std::vector<FrameRecord>& records) {
    for (const auto& r : records) {
      visual += r.visual_used;
      degenerate += r.degenerate;
      if (!r.has_pose) continue;
      ++frames;
      lio.push_back(r.lio_ms);
      vio.push_back(r.vio_ms);
      map.push_back(r.map_ms);
      map_wait.push_back(r.map_wait_ms);
      total.push_back(r.total_ms);
      if (r.visual_used) vio_per_visual_frame.push_back(r.vio_ms);
    }
  }
};

}  // namespace

void RunHealth::addFrame(const FrameRecord& f) {
  const Utime t = f.utime;
  const bool has_pose = f.has_pose, lidar_failed = f.lidar_failed, visual_used = f.visual_used;
  const bool degenerate = f.degenerate;
  if (first_ < 0) first_ = t;
  const double dt = prev_ >= 0 && t > prev_ ? toSeconds(t - prev_) : 0.0;
  prev_ = std::max(prev_, t);
  const std::string_view state = frameState(f);
  const bool lost = state == healthName(HealthState::Lost);
  if (lost && !prev_lost_) {
    ++lost_spans;
    if (first_lost_t < 0) first_lost_t = toSeconds(t);
  }
  prev_lost_ = lost;
  if (!has_pose) {
    if (first_pose_ < 0) initialising_s += dt;
    return;
  }
  if (first_pose_ < 0) first_pose_ = t;
  if (last_pose_ >= 0 && t > last_pose_) longest_gap_s = std::max(longest_gap_s, toSeconds(t - last_pose_));
  last_pose_ = std::max(last_pose_, t);
  if (lidar_failed) lidar_failed_s += dt;
  if (lidar_failed && !visual_used) imu_only_s += dt;
  if (degenerate) degenerate_s += dt;
  if (state == healthName(HealthState::Ok)) ++frames_ok;
  if (state == healthName(HealthState::Degraded)) ++frames_degraded, degraded_s += dt;
  if (lost) ++frames_lost, lost_s += dt;
}

double RunHealth::firstPoseDelaySeconds() const { return first_pose_ < 0 ? -1.0 : toSeconds(first_pose_ - first_); }

std::string RunHealth::json() const {
  std::ostringstream os;
  os << "{\"first_pose_delay_s\": " << num(firstPoseDelaySeconds()) << ", \"initialising_s\": " << num(initialising_s)
     << ", \"lidar_failed_s\": " << num(lidar_failed_s) << ", \"imu_only_s\": " << num(imu_only_s)
     << ", \"degenerate_s\": " << num(degenerate_s) << ", \"degraded_s\": " << num(degraded_s)
     << ", \"lost_s\": " << num(lost_s) << ", \"frames_ok\": " << frames_ok << ", \"frames_degraded\": " << frames_degraded
     << ", \"frames_lost\": " << frames_lost << ", \"lost_spans\": " << lost_spans
     << ", \"first_lost_t\": " << num(first_lost_t) << ", \"longest_pose_gap_s\": " << num(longest_gap_s);
  if (!no_pose_reason.empty()) os << ", \"no_pose_reason\": \"" << jsonEscape(no_pose_reason) << "\"";
  os << "}";
  return os.str();
}

void RunOutputs::writeStats(const MapSummary& map, double peak_rss_mb, const std::map<std::string, double>& counters,
                            const std::map<std::string, std::string>& notes, const RunHealth* health) const {
  const FrameTimes ft(records_);
  const std::string tmp = dir_ + "/stats.json.tmp";
  {
    std::ofstream os(tmp);
    if (!os) throw std::runtime_error(tmp + ": cannot open for writing");
    os << "{\n  \"frames\": " << records_.size() << ",\n  \"poses\": " << tum_.count()
       << ",\n  \"visual_frames\": " << ft.visual << ",\n  \"degenerate_frames\": " << ft.degenerate
       << ",\n  \"timed_frames\": " << ft.frames << ",\n  \"timing_ms\": {\n";
    writeSummary(os, "lio", summarize(ft.lio), false);
    writeSummary(os, "vio", summarize(ft.vio), false);
    writeSummary(os, "vio_per_visual_frame", summarize(ft.vio_per_visual_frame), false, true);
    writeSummary(os, "map", summarize(ft.map), false);
    writeSummary(os, "map_wait", summarize(ft.map_wait), false);
    writeSummary(os, "total", summarize(ft.total), true);
    os << "  },\n  \"peak_rss_mb\": " << num(peak_rss_mb) << ",\n  \"map\": {\"local_voxels\": " << map.local_voxels
       << ", \"visual_points_local\": " << map.visual_points_local
       << ", \"visual_points_longterm\": " << map.visual_points_longterm << ", \"bytes\": " << map.bytes;
    if (map.has_parts)
      os << ", \"bytes_lidar\": " << map.bytes_lidar << ", \"bytes_visual_local\": " << map.bytes_visual_local
         << ", \"bytes_visual_longterm\": " << map.bytes_visual_longterm << ", \"bytes_index\": " << map.bytes_index;
    os << "}";
    for (auto it = records_.rbegin(); it != records_.rend(); ++it)
      if (it->has_time_offset) {
        os << ",\n  \"camera\": {\"time_offset_estimate_s\": " << num(it->time_offset_s)
           << ", \"time_offset_sigma_s\": " << num(it->time_offset_sigma_s) << "}";
        break;
      }
    if (!counters.empty()) {
      os << ",\n  \"counters\": {";
      bool first = true;
      for (const auto& [k, v] : counters) {
        os << (first ? "" : ", ") << "\"" << jsonEscape(k) << "\": " << num(v);
        first = false;
      }
      os << "}";
    }
    if (health) os << ",\n  \"health\": " << health->json();
    for (const auto& [k, v] : notes) os << ",\n  \"" << jsonEscape(k) << "\": \"" << jsonEscape(v) << "\"";
    os << "\n}\n";
    if (!os) throw std::runtime_error(tmp + ": write failed");
  }
  std::filesystem::rename(tmp, dir_ + "/stats.json");
}

std::string RunOutputs::summary(double peak_rss_mb) const {
  const FrameTimes ft(records_);
  const auto l = summarize(ft.lio), v = summarize(ft.vio_per_visual_frame), t = summarize(ft.total);
  std::ostringstream os;
  os << std::fixed << std::setprecision(2);
  os << "frames " << records_.size() << " (poses " << tum_.count() << ", visual updates " << ft.visual
     << "; times over the " << ft.frames << " frames after initialisation)\n";
  os << "time per frame [ms]  lio median " << l.median << " p95 " << l.p95 << " | total mean " << t.mean
     << " median " << t.median << " p95 " << t.p95 << " max " << t.max << "\n";
  os << "visual update per visual frame [ms]  mean " << v.mean << " median " << v.median << " p95 " << v.p95
     << " max " << v.max << " (" << ft.vio_per_visual_frame.size() << " frames)\n";
  os << "peak RSS " << peak_rss_mb << " MB\n";
  return os.str();
}

}  // namespace livo
