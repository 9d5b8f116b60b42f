// Core of livo-estimator: LIVO_FRAME in; per frame LIVO_MAP_QUERY out and LIVO_SUBMAP back (request
// ids, a timeout), then LIVO_MAP_UPDATE, LIVO_ODOMETRY, LIVO_REGISTERED_SCAN and LIVO_ESTIMATOR_STATS
// out (FramePipeline, livo/estimation/frame_pipeline.hpp, does the estimation; RemoteMap reaches the
// map server through this node's MapClient).
//
// Frames are queued by the LCM handler and processed by poll() outside any handler; while a frame
// waits for its submap, poll() handles LCM messages (frames keep being queued; other answers are
// counted as late and dropped). A query without an answer within map_timeout_ms makes the frame
// continue with the planes it has (reported in the stats and the odometry status); after
// `fast_timeouts_after` consecutive timeouts the wait shrinks to fast_timeout_ms until the map server
// answers again, so a dead map server slows nothing down for long. Config section `estimator`.
//
// Restarts: after every frame with a pose the node publishes its whole filter state (LIVO_FILTER_STATE,
// filter_state_t), which the map server keeps with the IMU samples after it. At start the node asks
// for them (LIVO_RESUME_REQUEST); the first frame waits up to resume_wait_ms for the answer. With a
// state at most resume_max_gap_s older than that frame, the pipeline continues from it (propagated
// through the IMU samples of the outage) in the same world frame and map; otherwise it says why and
// initialises a new origin as usual. A frame whose IMU samples begin more than three sample periods
// after the filter state (frames lost upstream, e.g. a restarted preprocessor) gets the missing
// samples from the map server the same way.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/ms_histogram.hpp"
#include "livo/estimation/frame_pipeline.hpp"
#include "livo/estimation/remote_map.hpp"
#include "livo/common/timing.hpp"
#include "livo/io/channels.hpp"
#include "livo/io/resume_messages.hpp"
#include "livo/process/lcm_node.hpp"

#include <chrono>
#include <cstdint>
#include <deque>
#include <ostream>
#include <string>

namespace livo {

struct EstimatorNodeConfig {
  double map_timeout_ms = 250.0;   ///< wait for a submap, ms (wall clock: a network answer)
  double fast_timeout_ms = 20.0;   ///< wait after fast_timeouts_after timeouts in a row, ms
  int fast_timeouts_after = 3;
  int max_queued_frames = 100;     ///< older frames beyond this are dropped (counted, warned)
  /// Overload: with more than this many frames waiting behind the next one, and the last frame's LiDAR
  /// not degenerate, the next frame's image is left out (the visual update is the most expensive step).
  int shed_images_queued = 2;
  /// Overload: while more than this many frames wait, the oldest is dropped and its IMU samples merged
  /// into the next (the IMU is never shed). At most max_queued_frames.
  int shed_frames_queued = 10;
  double resume_wait_ms = 1000.0;  ///< at start, wait this long for the map server's last state (0: never resume)
  double resume_max_gap_s = 10.0;  ///< resume only when the first frame is at most this long after that state
  /// Not a key: the process's effective config (ConfigFile::effectiveLines()), sent with each resume
  /// request; a map server running another config answers with the keys that differ, and the node
  /// throws std::runtime_error naming them (livo-estimator exits).
  std::string config_lines;
  void load(const ConfigNode& section);  ///< section `estimator`
};

class EstimatorNode : public MapClient {
 public:
  EstimatorNode(LcmNode& lcm, PipelineConfig pipeline, EstimatorNodeConfig cfg, const ChannelConfig& channels,
                std::ostream* log);
  /// Processes the queued frames (call from the event loop, outside LCM handlers). Returns the count.
  std::size_t poll();

  // MapClient over LCM.
  bool request(const MapQuery& q, Submap& out) override;
  void send(const MapUpdate& u) override;

  /// How the node started (after the first frame): "resumed", "new origin: <why>" or "" before it.
  const std::string& startReport() const { return start_report_; }

  struct Counters {
    std::uint64_t frames = 0;             ///< processed
    std::uint64_t frames_dropped = 0;     ///< queue full (max_queued_frames), IMU merged into the next
    std::uint64_t frames_shed = 0;        ///< beyond shed_frames_queued, IMU merged into the next
    std::uint64_t images_shed = 0;        ///< beyond shed_images_queued on non-degenerate frames
    std::uint64_t odometry_published = 0;
    std::uint64_t queries = 0, timeouts = 0, late_submaps = 0, invalid_submaps = 0;
    std::uint64_t query_bytes = 0, submap_bytes = 0, update_bytes = 0;
    double max_round_trip_ms = 0.0, sum_round_trip_ms = 0.0;
    std::uint64_t answered = 0;
    std::uint64_t nonfinite_points = 0;
    std::uint64_t imu_gaps = 0;             ///< frames whose IMU began after a gap (frames lost upstream)
    std::uint64_t imu_bridged_samples = 0;  ///< samples the map server supplied for them
    Utime last_utime = 0;
  };
  const Counters& counters() const { return counters_; }
  const FramePipeline& pipeline() const { return pipeline_; }
  const RemoteMap& map() const { return map_; }
  std::string progressLine() const;
  std::string summary() const;

 private:
  struct Queued {
    Frame frame;
    std::size_t nonfinite = 0;
    std::chrono::steady_clock::time_point arrived;
    int shed_before = 0;  ///< frames dropped in front of this one (their IMU is in this one's)
  };
  /// Runs the pipeline on a frame (its image left out with `shed_image`) and publishes its outputs.
  void processFrame(Queued& q, bool shed_image);
  /// Before the first frame: waits (up to resume_wait_ms since the request) for the map server's answer
  /// and resumes from it when it fits the frame.
  bool startFrom(const Frame& first);  ///< true when it resumed
  static std::int64_t newRequestId();
  /// Throws std::runtime_error naming the keys when the map server answered that its config differs.
  void refuseOtherConfig() const;
  /// Publishes a resume request (a new id; the answer lands in resume_).
  void sendResumeRequest();
  /// Waits until the answer came or resume_wait_ms passed since the request; true when it came. The
  /// request is published again every 100 ms meanwhile (a map server started together with this
  /// estimator may not have been listening to the first one).
  bool awaitResumeAnswer();
  void publishResumeRequest();
  /// sendResumeRequest() + awaitResumeAnswer().
  bool askMapServer();
  /// `frame`'s IMU begins later than the filter state: prepends the map server's samples of the gap.
  bool bridgeImuGap(Frame& frame);

  LcmNode& lcm_;
  EstimatorNodeConfig cfg_;
  ChannelConfig channels_;
  std::ostream* log_;
  FramePipeline pipeline_;
  RemoteMap map_;  ///< the map server, through request() / send()
  /// Drops the oldest queued frame, merging its IMU samples (and counts) into the next one.
  void dropOldest();
  std::deque<Queued> queue_;
  bool last_degenerate_ = false;
  MsHistogram lag_ms_{1.0, 10000.0};  ///< frame arrival -> outputs, 1 ms bins to 10 s
  double max_lag_ms_ = 0.0;
  bool in_poll_ = false;
  // Pending request.
  std::int64_t waiting_for_ = -1;
  bool answered_ = false;
  Submap answer_;
  int timeouts_in_row_ = 0;
  Utime last_wait_said_ = -1;  ///< last "no pose yet" line (sensor time)
  bool announced_init_ = false;
  // Resume at start.
  std::int64_t resume_request_id_ = 0;
  bool resume_answered_ = false, started_ = false;
  Stopwatch since_resume_request_, since_resume_publish_;
  ResumeAnswer resume_;
  std::string start_report_;
  Counters counters_;
};

}  // namespace livo
