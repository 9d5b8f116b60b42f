// Core of livo-loop: loop closure beside the odometry (libs/loop LoopCloser, as livo-run --loop runs it).
//   LIVO_ODOMETRY (frames with a pose) + LIVO_REGISTERED_SCAN of the same frame -> LoopCloser::add, in
//       frame order. The estimator sends a frame's scan right after its odometry; an odometry frame waits
//       for its scan until two later frames or a later scan arrived, then goes on without one (a frame
//       without points sends no scan). Frames at or before one already taken are counted and dropped.
//   -> LIVO_MAP_CORRECTION after every keyframe (the new keyframe; all keyframes after a graph solve),
//       and at finish() after the last solve (all keyframes, `final`).
// Only message times are used.
#pragma once

#include "livo/io/channels.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/loop/loop_closer.hpp"
#include "livo/process/lcm_node.hpp"

#include <deque>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace livo {

class LoopNode {
 public:
  /// Subscribes on `lcm`.
  LoopNode(LcmNode& lcm, const ChannelConfig& channels, const LoopConfig& cfg, std::ostream* log);

  // Message handlers (validated structs; also called directly by tests).
  void onOdometry(const OdometryOutput& o);
  void onRegisteredScan(const RegisteredScan& s);

  /// Takes the frames still waiting, solves what is left and publishes the final correction. Call once.
  void finish();
  std::string progressLine() const;
  /// Multi-line summary for stdout at exit (the loop counters, the messages).
  std::string summary() const;

  const LoopCloser& closer() const { return closer_; }
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
  LoopCloser closer_;
  std::deque<OdometryOutput> pending_;
  std::map<Utime, std::vector<Eigen::Vector3f>> scans_;
  bool took_any_ = false;
  Utime last_taken_ = 0;
  std::map<std::string, double> counters_;
  bool finished_ = false;
};

}  // namespace livo
