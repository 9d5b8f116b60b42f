// Between the message thread and the drawing loop. The message thread only converts and pushes (it
// never waits for drawing, so the socket is always read and nothing upstream is slowed); the drawing
// loop takes everything pending once per frame. Scans queue up to `max_scans` and images up to one:
// what the loop has not taken by then is dropped, oldest first, and counted. Poses and statistics are
// small and always kept (the trajectory is complete whatever the drawing rate).
#pragma once

#include "livo/common/types.hpp"
#include "livo/loop/map_frame.hpp"
#include "livo/viewer/inputs.hpp"

#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <vector>

namespace livo::viewer {

/// Messages dropped by the viewer (never drawn), and rejected ones (failed validation upstream).
struct DropCounters {
  std::uint64_t scans = 0, images = 0, corrections = 0;
  std::uint64_t rejected = 0;  ///< set by the adapter: messages that failed decoding or validation
  std::uint64_t total() const { return scans + images + corrections + rejected; }
};

/// What the drawing loop takes in one go.
struct InboxBatch {
  std::vector<ScanInput> scans;             ///< oldest first
  std::vector<PoseInput> poses;             ///< in arrival order
  std::vector<FrameStatsInput> frame_stats;
  std::optional<MapStatsInput> map_stats;   ///< the latest
  std::optional<Image> image;               ///< the latest
  std::vector<MapCorrection> corrections;   ///< livo-loop's, in arrival order
  DropCounters drops;                       ///< totals since the start
  bool empty() const {
    return scans.empty() && poses.empty() && frame_stats.empty() && !map_stats && !image && corrections.empty();
  }
};

class Inbox {
 public:
  /// max_scans >= 1 (std::invalid_argument otherwise).
  explicit Inbox(std::size_t max_scans = 8);

  // Message thread.
  void pushScan(ScanInput scan);
  void pushPose(const PoseInput& pose);
  void pushFrameStats(const FrameStatsInput& stats);
  void pushMapStats(const MapStatsInput& stats);
  void pushImage(Image image);
  /// A correction of the loop closure. Corrections queue up to kMaxCorrections; beyond, the oldest
  /// that carries one keyframe goes (a full one after it holds that keyframe again; counted).
  void pushCorrection(MapCorrection correction);
  static constexpr std::size_t kMaxCorrections = 256;
  /// The adapter's count of rejected messages (a total, not an increment).
  void setRejected(std::uint64_t total);

  // Drawing loop.
  InboxBatch take();
  DropCounters drops() const;

 private:
  mutable std::mutex mutex_;
  std::size_t max_scans_;
  std::deque<ScanInput> scans_;
  std::vector<PoseInput> poses_;
  std::vector<FrameStatsInput> frame_stats_;
  std::optional<MapStatsInput> map_stats_;
  std::optional<Image> image_;
  std::vector<MapCorrection> corrections_;
  DropCounters drops_;
};

}  // namespace livo::viewer
