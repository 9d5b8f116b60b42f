// Core of livo-preprocess: raw sensor messages in (LIVO_IMU, LIVO_LIDAR, LIVO_CAMERA), estimator frames
// out (LIVO_FRAME). Each message is validated (decode + fromMsg; rejects are counted and warned about
// at a limited rate), images are converted to 8-bit gray (toGray8; the estimator scales them), and the
// Recombiner (livo/sensors/recombiner.hpp) recuts the LiDAR stream at the image times. Every frame it
// completes is published at once. Counters go to the log every `report_interval_s` of message time.
#pragma once

#include "livo/io/channels.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/sensors/recombiner.hpp"

#include <cstdint>
#include <functional>
#include <ostream>
#include <string>

namespace livo {

class PreprocessNode {
 public:
  /// Subscribes to channels.imu / lidar / camera on `lcm` and publishes on channels.frame. Throws
  /// std::invalid_argument for an invalid PreprocessConfig.
  PreprocessNode(LcmNode& lcm, const PreprocessConfig& cfg, const ChannelConfig& channels, std::ostream* log,
                 double report_interval_s = 5.0);

  /// End of input: flushes the recombiner and publishes the frames it still held.
  void finish();

  struct Counters {
    std::uint64_t frames_published = 0;
    std::uint64_t bytes_published = 0;
    std::uint64_t frames_with_image = 0;
    std::uint64_t nonfinite_points = 0;   ///< dropped while converting scans (fromMsg)
    std::uint64_t images_unconvertible = 0;  ///< toGray8 failed (counted as rejected too)
    std::uint64_t publish_errors = 0;
    Utime last_frame_utime = 0;
  };
  const Counters& counters() const { return counters_; }
  const Recombiner& recombiner() const { return recombiner_; }
  /// One line of counters (frames, inputs, rejects, drops).
  std::string progressLine() const;
  /// Multi-line summary for the end of a run: inputs per channel, frames, the recombiner's counters.
  std::string summary() const;

 private:
  Validation onImu(const livo::imu_t& m);
  Validation onLidar(const livo::lidar_scan_t& m);
  Validation onCamera(const void* data, std::size_t size);
  /// Publishes every frame the recombiner has completed.
  void publishReady();

  LcmNode& lcm_;
  ChannelConfig channels_;
  std::ostream* log_;
  double report_interval_s_;
  Recombiner recombiner_;
  Counters counters_;
  bool have_report_time_ = false;
  Utime last_report_utime_ = 0;
  std::uint64_t frames_at_last_report_ = 0;
};

}  // namespace livo
