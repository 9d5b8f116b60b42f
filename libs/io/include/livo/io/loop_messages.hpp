// Conversion of the loop closure's message (map_correction_t, livo-loop -> livo-exporter, livo-viewer).
// Validation as in convert.hpp: fromMsg() leaves `out` untouched on failure and names the field.
#pragma once

#include "livo/io/convert.hpp"
#include "livo/loop/map_frame.hpp"

#include <livo/map_correction_t.hpp>

namespace livo {

livo::map_correction_t toMsg(const MapCorrection& c);

/// map_correction_t: utime >= 0; a finite T_map_odom with a non-zero quaternion; keyframes_total,
/// solves, first_keyframe >= 0; num_keyframes and num_loops in [0, lim.max_keyframes] matching their
/// arrays; first_keyframe + num_keyframes <= keyframes_total; keyframe times >= 0 and increasing; finite
/// poses with non-zero quaternions (normalised on the way in); loop edges from < to < keyframes_total.
Validation fromMsg(const livo::map_correction_t& m, MapCorrection& out, const MessageLimits& lim = {});

}  // namespace livo
