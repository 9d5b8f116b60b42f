// The one mapping from what a frame did (FrameResult) to what the outputs report about it: the
// estimator's statistics (LIVO_ESTIMATOR_STATS, EstimatorStats) and the output row (FrameRecord:
// frames.csv, stats.json). livo-run, livo-estimator and livo-exporter all go through these two
// functions, so a field means the same in one process and in four:
//   livo-run:        FrameResult -> frameStats -> applyStats -> FrameRecord
//   four processes:  FrameResult -> frameStats -> LCM -> livo-exporter: applyStats -> FrameRecord
// Times (ms, wall clock of the estimator's process):
//   lio_ms       propagation, undistortion and the LiDAR update;
//   vio_ms       the photometric update (0 when not run);
//   map_ms       the map's work done in the estimator's process: scan insertion + slides / evictions in
//                one process; with the map server only encoding and sending the update (the server's
//                own work is in its statistics, LIVO_MAP_STATS);
//   map_wait_ms  waiting for the map server's answers (0 in one process);
//   total_ms     the whole frame.
#pragma once

#include "livo/estimation/frame_result.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/io/run_outputs.hpp"

#include <cstddef>
#include <cstdint>

namespace livo {

/// The frame's statistics as the estimator publishes them. `dropped_points`: points the frame lost to
/// NaN / range / blind before the pipeline (clamped to int32).
EstimatorStats frameStats(const FrameResult& f, Utime utime, std::int64_t frame_index, std::size_t dropped_points);

/// Copies the statistics into an output row: every field but the pose, has_pose and map_bytes.
void applyStats(FrameRecord& rec, const EstimatorStats& s);

}  // namespace livo
