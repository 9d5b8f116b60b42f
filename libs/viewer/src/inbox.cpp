#include "livo/viewer/inbox.hpp"

#include <stdexcept>

namespace livo::viewer {

Inbox::Inbox(std::size_t max_scans) : max_scans_(max_scans) {
  if (max_scans_ == 0) throw std::invalid_argument("Inbox: max_scans must be >= 1");
}

void Inbox::pushScan(ScanInput scan) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (scans_.size() >= max_scans_) {
    scans_.pop_front();
    ++drops_.scans;
  }
  scans_.push_back(std::move(scan));
}

void Inbox::pushPose(const PoseInput& pose) {
  std::lock_guard<std::mutex> lock(mutex_);
  poses_.push_back(pose);
}

void Inbox::pushFrameStats(const FrameStatsInput& stats) {
  std::lock_guard<std::mutex> lock(mutex_);
  frame_stats_.push_back(stats);
}

void Inbox::pushMapStats(const MapStatsInput& stats) {
  std::lock_guard<std::mutex> lock(mutex_);
  map_stats_ = stats;
}

void Inbox::pushImage(Image image) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (image_) ++drops_.images;
  image_ = std::move(image);
}

void Inbox::pushCorrection(MapCorrection correction) {
  std::lock_guard<std::mutex> lock(mutex_);
  corrections_.push_back(std::move(correction));
  if (corrections_.size() <= kMaxCorrections) return;
  // Too many not taken: a full correction makes every one before it redundant.
  for (std::size_t i = corrections_.size(); i-- > 0;)
    if (corrections_[i].first == 0 && corrections_[i].keyframes.size() == std::size_t(corrections_[i].keyframes_total)) {
      drops_.corrections += i;
      corrections_.erase(corrections_.begin(), corrections_.begin() + std::ptrdiff_t(i));
      return;
    }
  corrections_.erase(corrections_.begin());
  ++drops_.corrections;
}

void Inbox::setRejected(std::uint64_t total) {
  std::lock_guard<std::mutex> lock(mutex_);
  drops_.rejected = total;
}

InboxBatch Inbox::take() {
  InboxBatch b;
  std::lock_guard<std::mutex> lock(mutex_);
  b.scans.assign(std::make_move_iterator(scans_.begin()), std::make_move_iterator(scans_.end()));
  scans_.clear();
  b.poses.swap(poses_);
  b.frame_stats.swap(frame_stats_);
  b.map_stats.swap(map_stats_);
  b.image.swap(image_);
  b.corrections.swap(corrections_);
  b.drops = drops_;
  return b;
}

DropCounters Inbox::drops() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return drops_;
}

}  // namespace livo::viewer
