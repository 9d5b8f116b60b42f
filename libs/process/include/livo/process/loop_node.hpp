// Core of livo-loop: loop closure beside the odometry (libs/loop LoopCloser, as livo-run --loop runs it).
//   LIVO_ODOMETRY (frames with a pose) + LIVO_REGISTERED_SCAN of the same frame -> LoopCloser::add, in
//       frame order. The estimator sends a frame's scan right after its odometry; an odometry frame waits
//       for its scan until two later frames or a later scan arrived, then goes on without one (a frame
//       without points sends no scan). Frames at or before one already taken are counted and dropped.
//   -> LIVO_MAP_CORRECTION after every keyframe (the new keyframe; all keyframes after a graph solve),
//       and at finish() after the last solve (all keyframes, `final`).
// With a site map (livo-loop --prior-map) the frames go to a Relocaliser instead: every match publishes
// the new anchor (a keyframe with its map pose), finish() all anchors; consumers treat them as above.
// Only message times are used.
#pragma once

#include "livo/io/channels.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/loop/loop_closer.hpp"
#include "livo/loop/relocaliser.hpp"
#include "livo/loop/site_map.hpp"
#include "livo/process/lcm_node.hpp"

#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace livo {

class LoopNode {
 public:
  /// Subscribes on `lcm`. With `prior_map`: localises in that site map (it must outlive the node).
  LoopNode(LcmNode& lcm, const ChannelConfig& channels, const LoopConfig& cfg, std::ostream* log,
           SiteMap* prior_map = nullptr);

  // Message handlers (validated structs; also called directly by tests).
  void onOdometry(const OdometryOutput& o);
  void onRegisteredScan(const RegisteredScan& s);

  /// Takes the frames still waiting, solves what is left and publishes the final correction. Call once.
  void finish();
  std::string progressLine() const;
  /// Multi-line summary for stdout at exit (the loop counters, the messages).
  std::string summary() const;

  /// The loop closer (loop closure) or the relocaliser (with a site map): the one in use.
  const LoopCloser* closer() const { return closer_ ? &*closer_ : nullptr; }
  const Relocaliser* relocaliser() const { return reloc_.get(); }
  /// Time of the last frame handed to the loop closer (0 before the first).
  Utime lastFrameTime() const { return last_taken_; }
  const std::map<std::string, double>& counters() const { return counters_; }

 private:
  /// Hands the waiting frames to the loop closer (see the header comment); `all`: every one.
  void pump(bool all);
  void take(const OdometryOutput& o, const std::vector<Eigen::Vector3f>* scan);
  void publish(bool all, bool final);
  /// False (and counted) when `t` is at or before the last frame taken.
  bool accept(Utime t, const char* what);

  static constexpr std::size_t kWaitFrames = 2;  ///< odometry frames waiting for the first one's scan
  static constexpr std::size_t kMaxScans = 8;    ///< scans held for odometry that has not arrived

  LcmNode& lcm_;
  ChannelConfig channels_;
  std::ostream* log_;
  std::optional<LoopCloser> closer_;
  std::unique_ptr<Relocaliser> reloc_;
  std::deque<OdometryOutput> pending_;
  std::map<Utime, std::vector<Eigen::Vector3f>> scans_;
  bool took_any_ = false;
  Utime last_taken_ = 0;
  std::map<std::string, double> counters_;
  bool finished_ = false;
};

}  // namespace livo
