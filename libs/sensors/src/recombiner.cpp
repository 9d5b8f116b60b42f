#include "livo/sensors/recombiner.hpp"

#include "livo/sensors/downsample.hpp"

#include <algorithm>
#include <utility>

namespace livo {

namespace {

bool byTime(const StampedPoint& a, const StampedPoint& b) { return a.utime < b.utime; }

bool validGray8(const Image& im) {
  if (im.format != PixelFormat::Gray8) return false;
  if (im.width <= 0 || im.height <= 0 || im.width > 65535 || im.height > 65535) return false;
  if (im.row_stride < im.width) return false;
  const std::size_t needed =
      static_cast<std::size_t>(im.row_stride) * static_cast<std::size_t>(im.height - 1) + im.width;
  return im.data.size() >= needed;
}

}  // namespace

Recombiner::Recombiner(const PreprocessConfig& cfg) : cfg_(cfg) { cfg_.validate(); }

void Recombiner::noteTime(Utime t) {
  max_seen_ = have_any_ ? std::max(max_seen_, t) : t;
  have_any_ = true;
}

bool Recombiner::timedOut(Utime t, double timeout_s) const {
  return flushing_ || (have_any_ && max_seen_ - t > fromSeconds(timeout_s));
}

// ---------------------------------------------------------------- forward jumps

Recombiner::JumpGuard::Decision Recombiner::JumpGuard::check(bool have_prev, Utime prev, Utime t, Utime max_jump) {
  Decision d;
  if (holding) {
    holding = false;
    if (t > held_t && t - held_t <= max_jump) {  // the stream goes on from the held stamp: confirmed
      d.release_held = true;
      d.released_jump = held_is_jump;
      return d;
    }
    d.discard_held = true;
  }
  if (!have_prev || t - prev > max_jump) {
    holding = true;
    held_is_jump = have_prev;
    held_t = t;
    d.hold_new = true;
  }
  return d;
}

void Recombiner::flush() {
  // Held items: the first item of a stream cannot be contradicted any more and is used; an
  // unconfirmed jump is dropped as a glitch.
  if (imu_guard_.holding) {
    if (imu_guard_.held_is_jump)
      ++stats_.imu_glitches;
    else
      acceptImu(held_imu_);
  }
  if (scan_guard_.holding) {
    if (scan_guard_.held_is_jump) {
      ++stats_.scans_glitches;
      stats_.points_in += held_scan_.points.size();
      stats_.points_out_of_order += held_scan_.points.size();
    } else {
      acceptScan(held_scan_, held_scan_start_);
    }
    held_scan_ = LidarScan{};
  }
  if (image_guard_.holding) {
    if (image_guard_.held_is_jump)
      ++stats_.images_glitches;
    else if (acceptImageStamp(held_image_.utime))
      images_.push_back(std::move(held_image_));
    held_image_ = Image{};
  }
  imu_guard_.holding = scan_guard_.holding = image_guard_.holding = false;
  flushing_ = true;
  trimBuffers();
}

// ---------------------------------------------------------------- IMU

void Recombiner::addImu(const ImuSample& sample) {
  ++stats_.imu_in;
  if (!sample.gyro.allFinite() || !sample.accel.allFinite()) {
    ++stats_.imu_invalid;
    return;
  }
  ImuSample m = sample;
  m.utime = sample.utime - fromSeconds(cfg_.imu_time_offset_s);
  const auto d = imu_guard_.check(have_imu_, imu_newest_, m.utime, fromSeconds(cfg_.max_time_jump_s));
  if (d.discard_held) ++stats_.imu_glitches;
  if (d.release_held) {
    if (d.released_jump) ++stats_.forward_jumps;
    acceptImu(held_imu_);
  }
  if (d.hold_new)
    held_imu_ = m;
  else
    acceptImu(m);
}

void Recombiner::acceptImu(const ImuSample& m) {
  const Utime t = m.utime;
  if (have_imu_) {
    if (t == imu_newest_) {
      ++stats_.imu_duplicates;
      return;
    }
    if (t < imu_newest_) {
      ++stats_.imu_out_of_order;
      return;
    }
    const double step_s = toSeconds(t - imu_newest_);
    stats_.imu_max_gap_s = std::max(stats_.imu_max_gap_s, step_s);
    if (step_s > cfg_.imuGapThresholdS()) ++stats_.imu_gaps;
  }
  imu_.push_back(m);
  imu_newest_ = t;
  have_imu_ = true;
  noteTime(t);
  trimBuffers();
}

// ---------------------------------------------------------------- LiDAR

void Recombiner::addScan(const LidarScan& scan) {
  ++stats_.scans_in;
  const Utime start = scan.utime + fromSeconds(cfg_.lidar_time_offset_s);
  const auto d = scan_guard_.check(have_scan_, last_scan_start_, start, fromSeconds(cfg_.max_time_jump_s));
  if (d.discard_held) {
    ++stats_.scans_glitches;
    stats_.points_in += held_scan_.points.size();
    stats_.points_out_of_order += held_scan_.points.size();
  }
  if (d.release_held) {
    if (d.released_jump) ++stats_.forward_jumps;
    acceptScan(held_scan_, held_scan_start_);
  }
  if (d.release_held || d.discard_held) held_scan_ = LidarScan{};
  if (d.hold_new) {
    held_scan_ = scan;
    held_scan_start_ = start;
  } else {
    acceptScan(scan, start);
  }
}

void Recombiner::acceptScan(const LidarScan& scan, Utime start) {
  if (have_scan_ && start <= last_scan_start_) {  // backward jump or repeated scan: drop it whole
    ++stats_.scans_out_of_order;
    stats_.points_in += scan.points.size();
    stats_.points_out_of_order += scan.points.size();
    return;
  }
  const bool first_scan = !have_scan_;
  have_scan_ = true;
  last_scan_start_ = start;
  if (!scan.sensor.empty()) sensor_ = scan.sensor;

  scratch_.clear();
  const Utime coverage = filterScanPoints(scan, start, cfg_, stats_, scratch_);
  lidar_newest_ = first_scan ? coverage : std::max(lidar_newest_, coverage);
  noteTime(coverage);
  if (scratch_.empty()) {
    ++stats_.scans_empty;
    trimBuffers();
    return;
  }
  if (!std::is_sorted(scratch_.begin(), scratch_.end(), byTime))
    std::stable_sort(scratch_.begin(), scratch_.end(), byTime);
  if (!lidar_started_) {  // the first sweep starts at (and includes) the first point time
    lidar_started_ = true;
    sweep_start_ = scratch_.front().utime;
    floor_ = sweep_start_ - 1;
  }
  // Points at or before an emitted frame cannot join any sweep.
  const auto first_new = std::upper_bound(scratch_.begin(), scratch_.end(), StampedPoint{{}, floor_}, byTime);
  stats_.points_late += static_cast<std::size_t>(first_new - scratch_.begin());
  if (first_new == scratch_.end()) {
    trimBuffers();
    return;
  }
  // Scan ends are frame ends in LiDAR-only mode and fallback frame ends in camera mode.
  const Utime end = scratch_.back().utime;
  const bool scan_frames = !cfg_.camera_enabled || cfg_.image_wait_timeout_s > 0.0;
  if (scan_frames && (scan_ends_.empty() || end > scan_ends_.back())) scan_ends_.push_back(end);

  // Merge into the time-sorted buffer (usually a plain append: scans arrive in time order).
  const std::size_t old_size = points_.size();
  points_.insert(points_.end(), first_new, scratch_.end());
  if (old_size > 0 && points_[old_size].utime < points_[old_size - 1].utime)
    std::inplace_merge(points_.begin(), points_.begin() + static_cast<std::ptrdiff_t>(old_size), points_.end(),
                       byTime);
  trimBuffers();
}

// ---------------------------------------------------------------- images

bool Recombiner::screenImage(const Image& image, Utime& t) {
  ++stats_.images_in;
  if (!cfg_.camera_enabled) {
    ++stats_.images_ignored;
    return false;
  }
  if (!validGray8(image)) {
    ++stats_.images_invalid;
    return false;
  }
  t = image.utime + fromSeconds(cfg_.camera_time_offset_s);
  return true;
}

bool Recombiner::acceptImageStamp(Utime t) {
  if (have_frame_ && t <= sweep_start_) {  // sweep_start_ is the last frame time here
    ++stats_.images_stale;
    return false;
  }
  if (have_image_seen_ && t <= last_image_seen_) {
    ++stats_.images_out_of_order;
    return false;
  }
  have_image_seen_ = true;
  last_image_seen_ = t;
  noteTime(t);
  if (decimation_counter_++ % static_cast<std::uint64_t>(cfg_.image_decimation) != 0) {
    ++stats_.images_decimated;
    return false;
  }
  if (have_image_kept_ && t - last_image_kept_ < fromSeconds(cfg_.min_frame_interval_s)) {
    ++stats_.images_too_close;
    return false;
  }
  have_image_kept_ = true;
  last_image_kept_ = t;
  return true;
}

template <class ImageRef>
void Recombiner::addImageImpl(ImageRef&& image) {
  Utime t = 0;
  if (!screenImage(image, t)) return;
  const auto d = image_guard_.check(have_image_seen_, last_image_seen_, t, fromSeconds(cfg_.max_time_jump_s));
  if (d.discard_held) ++stats_.images_glitches;
  if (d.release_held) {
    if (d.released_jump) ++stats_.forward_jumps;
    if (acceptImageStamp(held_image_.utime)) images_.push_back(std::move(held_image_));
  }
  if (d.release_held || d.discard_held) held_image_ = Image{};
  if (d.hold_new) {
    held_image_ = std::forward<ImageRef>(image);
    held_image_.utime = t;
  } else if (acceptImageStamp(t)) {
    images_.push_back(std::forward<ImageRef>(image));
    images_.back().utime = t;
  }
  trimBuffers();
}

void Recombiner::addImage(const Image& image) { addImageImpl(image); }
void Recombiner::addImage(Image&& image) { addImageImpl(std::move(image)); }

// ---------------------------------------------------------------- frames

bool Recombiner::nextFrame(Frame& out) {
  for (;;) {
    if (!cfg_.camera_enabled) {  // LiDAR-only: one frame per scan end
      if (scan_ends_.empty()) return false;
      const Utime e = scan_ends_.front();
      if (!imuReaches(e) && !timedOut(e, cfg_.wait_timeout_s)) return false;
      cutFrame(e, false, out);
      return true;
    }

    // Camera mode. A scan end with no image within image_wait_timeout_s after it is a frame too, and
    // so is one whose next image comes only after the next scan end (the camera skipped a LiDAR
    // period, e.g. when it resumes after an outage): frames stay at the LiDAR rate.
    const bool have_image = !images_.empty();
    const Utime t_c = have_image ? images_.front().utime : 0;
    if (cfg_.image_wait_timeout_s > 0.0 && !scan_ends_.empty()) {
      const Utime e = scan_ends_.front();
      const bool skipped = have_image && scan_ends_.size() > 1 && t_c > scan_ends_[1];
      if (skipped || ((!have_image || t_c > e + fromSeconds(cfg_.image_wait_timeout_s)) &&
                      timedOut(e, cfg_.image_wait_timeout_s))) {
        if (!imuReaches(e) && !timedOut(e, cfg_.wait_timeout_s)) return false;
        cutFrame(e, false, out);
        return true;
      }
    }
    if (!have_image) return false;
    if (!lidar_started_) {  // no LiDAR point yet: wait, but not forever
      if (!timedOut(t_c, cfg_.wait_timeout_s)) return false;
      images_.pop_front();
      ++stats_.images_no_lidar;
      continue;
    }
    if (t_c <= sweep_start_) {
      // Before the first frame: the image precedes the first LiDAR point. (Later, images at or
      // before the last frame are rejected on arrival and fallback frames stop before images.)
      images_.pop_front();
      ++(have_frame_ ? stats_.images_stale : stats_.images_no_lidar);
      continue;
    }
    const bool covered = lidar_newest_ >= t_c && imuReaches(t_c);
    if (!covered && !timedOut(t_c, cfg_.wait_timeout_s)) return false;
    cutFrame(t_c, true, out);
    return true;
  }
}

void Recombiner::cutFrame(Utime t_end, bool with_image, Frame& out) {
  out.utime = t_end;
  out.sweep_start_utime = sweep_start_;

  // Sweep: buffered points with time in (floor_, t_end], already sorted; offsets from the sweep start.
  out.sweep.utime = sweep_start_;
  out.sweep.sensor = sensor_;
  const auto end = std::upper_bound(points_.begin(), points_.end(), StampedPoint{{}, t_end}, byTime);
  const auto n = static_cast<std::size_t>(end - points_.begin());
  out.sweep.points.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.sweep.points[i] = points_[i].point;
    out.sweep.points[i].time_offset_s = static_cast<float>(toSeconds(points_[i].utime - sweep_start_));
  }
  points_.erase(points_.begin(), end);
  if (cfg_.voxel_leaf_m > 0.0 && n > 0) {
    std::vector<LidarPoint> down = voxelDownsample(out.sweep.points, static_cast<float>(cfg_.voxel_leaf_m));
    stats_.points_voxel_merged += n - down.size();
    std::stable_sort(down.begin(), down.end(),
                     [](const LidarPoint& a, const LidarPoint& b) { return a.time_offset_s < b.time_offset_s; });
    out.sweep.points = std::move(down);
  }
  stats_.points_emitted += out.sweep.points.size();
  if (out.sweep.points.empty()) ++stats_.empty_sweeps;
  if (!lidar_started_ || lidar_newest_ < t_end) ++stats_.frames_lidar_incomplete;

  // IMU: from the last sample at or before the sweep start to the first at or after t_end.
  out.imu.clear();
  if (!imu_.empty()) {
    std::size_t i0 = 0;
    while (i0 + 1 < imu_.size() && imu_[i0 + 1].utime <= sweep_start_) ++i0;
    std::size_t i1 = i0;
    while (i1 + 1 < imu_.size() && imu_[i1].utime < t_end) ++i1;
    out.imu.assign(imu_.begin() + static_cast<std::ptrdiff_t>(i0), imu_.begin() + static_cast<std::ptrdiff_t>(i1 + 1));
  }
  if (out.imu.empty() || out.imu.front().utime > sweep_start_ || out.imu.back().utime < t_end)
    ++stats_.frames_imu_incomplete;

  if (with_image) {
    out.has_image = true;
    out.image = std::move(images_.front());
    images_.pop_front();
    ++stats_.images_used;
  } else {
    out.has_image = false;
    out.image = Image{};
    ++stats_.frames_without_image;
  }
  ++stats_.frames;

  sweep_start_ = t_end;
  floor_ = t_end;
  have_frame_ = true;
  while (!scan_ends_.empty() && scan_ends_.front() <= t_end) scan_ends_.pop_front();
  trimBuffers();
}

void Recombiner::trimBuffers() {
  if (!have_any_) return;
  const Utime cut = max_seen_ - fromSeconds(cfg_.max_buffer_s);

  // Before the first frame there is no previous frame to stay contiguous with: the first sweep
  // starts at the buffer window instead (the points before it are counted as overflow below).
  if (lidar_started_ && !have_frame_ && sweep_start_ < cut) {
    sweep_start_ = cut;
    floor_ = cut - 1;
  }
  // IMU samples before the one at or before the sweep start are never needed again.
  const Utime keep_from = lidar_started_ ? sweep_start_ : cut;
  while (imu_.size() >= 2 && imu_[1].utime <= keep_from) imu_.pop_front();
  // Frames stalled for longer than max_buffer_s: drop needed samples too (keeping one at or before cut).
  while (imu_.size() >= 2 && imu_[1].utime <= cut) {
    imu_.pop_front();
    ++stats_.imu_overflow;
  }
  if (!points_.empty() && points_.front().utime < cut) {
    const auto it = std::lower_bound(points_.begin(), points_.end(), StampedPoint{{}, cut}, byTime);
    stats_.points_overflow += static_cast<std::size_t>(it - points_.begin());
    points_.erase(points_.begin(), it);
  }
  while (!scan_ends_.empty() && (scan_ends_.front() < cut || scan_ends_.front() <= floor_)) scan_ends_.pop_front();
  while (!images_.empty() && images_.front().utime < cut) {
    images_.pop_front();
    ++stats_.images_overflow;
  }
}

}  // namespace livo
