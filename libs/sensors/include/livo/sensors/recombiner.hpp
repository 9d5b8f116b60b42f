// Scan recombination (docs/algorithms.md section 6): recuts the LiDAR stream into estimator frames.
//
// Camera mode (camera_enabled): one frame per kept image, at its time t_c. The sweep holds the points
// with absolute time in (t_last, t_c] (t_last = previous frame time; the first sweep starts at, and
// includes, the first LiDAR point time), sorted by time, offsets re-referenced to t_last; later points
// are carried over to the next frame. The frame is emitted once the newest LiDAR point time and the
// newest IMU time both reach t_c. A LiDAR scan end that no image follows within image_wait_timeout_s
// becomes a frame without image (the camera stopped or is slow), so the estimator keeps running; so
// does a scan end whose next image comes after the next scan end (the camera skipped a period).
// LiDAR-only mode: one frame per non-empty scan, ending at its last (kept) point time.
//
// Every frame carries the IMU samples covering [t_last, t_c]: from the last one at or before t_last to
// the first one at or after t_c (when they exist; frames_imu_incomplete counts the others).
//
// Sensor times: IMU t - imu.time_offset_s, scans t + lidar.time_offset_s, images
// t + camera.time_offset_s; all frame and image stamps are on this corrected clock.
//
// Robustness (everything is counted in PreprocessStats, nothing throws, nothing blocks):
// - a stamp going backwards in any stream drops the offending item (IMU sample, whole scan, image);
//   equal IMU stamps are duplicates; points at or before an emitted frame are late;
// - a stamp jumping forward by more than max_time_jump_s is held until the next item of its stream:
//   if that one follows it, the jump was real (both are used); otherwise the held item was a glitch
//   and is dropped (a single bad future stamp would otherwise stall its stream and time out all).
//   The first item of each stream is held the same way, as there is nothing to compare it with;
// - waits are measured in sensor time: when the newest stamp of any stream is wait_timeout_s past a
//   frame whose LiDAR or IMU data is missing, the frame is emitted anyway (a stopped sensor never
//   blocks), possibly with an empty sweep;
// - points and IMU samples older than max_buffer_s before the newest stamp are dropped.
// Frames are strictly increasing in time.
//
// Usage: add* in arrival order and drain with `while (r.nextFrame(f)) ...` after each add (data
// older than max_buffer_s is dropped, so do not batch long stretches); at end of input call flush()
// and drain again (flush makes every wait time out). Single-threaded: the caller serialises calls.
//
// Known limits: LiDAR-only frames are cut as soon as the IMU covers the scan end, so points of the
// next scan that overlap the previous one in time (Ouster sweeps last ~0.1005 s) arrive late and are
// dropped (counted; ~0.1% of a scan). A stream whose clock is consistently offset from the others
// (wrong time_offset_s) is not detected here.
#pragma once

#include "livo/common/types.hpp"
#include "livo/sensors/preprocess_config.hpp"
#include "livo/sensors/preprocess_points.hpp"
#include "livo/sensors/preprocess_stats.hpp"

#include <deque>
#include <vector>

namespace livo {

class Recombiner {
 public:
  /// Throws std::invalid_argument for an invalid config (PreprocessConfig::validate).
  explicit Recombiner(const PreprocessConfig& cfg);

  void addImu(const ImuSample& sample);
  /// Applies the time offset and the point filters (filterScanPoints), buffers the kept points.
  void addScan(const LidarScan& scan);
  /// Gray8 only (the caller converts colour or compressed images). Applies the time offset.
  void addImage(const Image& image);
  void addImage(Image&& image);

  /// Pops the next complete frame into `out`; false when none is ready yet.
  bool nextFrame(Frame& out);
  /// End of input: every wait times out from now on, so nextFrame emits all that can be emitted.
  /// Items held for an unconfirmed forward jump are dropped as glitches. Points after the last frame
  /// stay buffered (pendingPoints()).
  void flush();

  const PreprocessStats& stats() const { return stats_; }
  const PreprocessConfig& config() const { return cfg_; }
  std::size_t pendingPoints() const { return points_.size(); }
  std::size_t pendingImages() const { return images_.size(); }
  std::size_t bufferedImu() const { return imu_.size(); }

 private:
  /// Holds the first item of a stream, and an item whose stamp jumps forward, until the next item of
  /// the stream confirms its stamp (follows it within max_time_jump_s).
  struct JumpGuard {
    bool holding = false;
    bool held_is_jump = false;  ///< held for a jump (not as the first item of the stream)
    Utime held_t = 0;
    struct Decision {
      bool discard_held = false;  ///< the held item was a glitch
      bool release_held = false;  ///< the held item is confirmed: process it before the new one
      bool released_jump = false; ///< ... and it was a forward jump
      bool hold_new = false;      ///< the new item jumps (or is first): hold it instead of processing it
    };
    Decision check(bool have_prev, Utime prev, Utime t, Utime max_jump);
  };

  void acceptImu(const ImuSample& sample);  // stamp already corrected
  void acceptScan(const LidarScan& scan, Utime start);
  /// Checks and counts an image; true (with its corrected stamp) when it is to be kept.
  bool screenImage(const Image& image, Utime& t);
  /// Order, decimation and spacing checks of a screened image; true when it is to be buffered.
  bool acceptImageStamp(Utime t);
  template <class ImageRef>
  void addImageImpl(ImageRef&& image);
  bool timedOut(Utime t, double timeout_s) const;
  bool imuReaches(Utime t) const { return have_imu_ && imu_newest_ >= t; }
  void noteTime(Utime t);
  /// Cuts the frame ending at t_end (taking the front image when `with_image`).
  void cutFrame(Utime t_end, bool with_image, Frame& out);
  /// Drops IMU samples no frame needs any more and data older than max_buffer_s.
  void trimBuffers();

  PreprocessConfig cfg_;
  PreprocessStats stats_;
  bool flushing_ = false;

  Utime max_seen_ = 0;  ///< newest accepted stamp over all streams
  bool have_any_ = false;

  JumpGuard imu_guard_, scan_guard_, image_guard_;
  ImuSample held_imu_;
  LidarScan held_scan_;
  Utime held_scan_start_ = 0;
  Image held_image_;

  // IMU: strictly increasing stamps.
  std::deque<ImuSample> imu_;
  Utime imu_newest_ = 0;
  bool have_imu_ = false;

  // LiDAR: points sorted by time, all > floor_.
  std::vector<StampedPoint> points_;
  std::vector<StampedPoint> scratch_;
  std::deque<Utime> scan_ends_;  ///< strictly increasing ends of buffered scans (> sweep_start_)
  std::string sensor_;
  Utime last_scan_start_ = 0;
  bool have_scan_ = false;
  Utime lidar_newest_ = 0;     ///< LiDAR coverage: newest valid point time
  bool lidar_started_ = false;  ///< a non-empty scan arrived: sweep_start_ is defined

  // Frames: the next sweep starts at sweep_start_ and holds points with time > floor_.
  Utime sweep_start_ = 0;
  Utime floor_ = 0;
  bool have_frame_ = false;

  // Images: kept images waiting for their frame, strictly increasing stamps.
  std::deque<Image> images_;
  Utime last_image_seen_ = 0;  ///< newest valid in-order image (kept or not)
  bool have_image_seen_ = false;
  Utime last_image_kept_ = 0;
  bool have_image_kept_ = false;
  std::uint64_t decimation_counter_ = 0;
};

}  // namespace livo
