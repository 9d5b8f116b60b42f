#include "livo/io/frame_row.hpp"

#include <algorithm>

namespace livo {

EstimatorStats frameStats(const FrameResult& f, Utime utime, std::int64_t frame_index, std::size_t dropped_points) {
  EstimatorStats st;
  st.utime = utime;
  st.frame_index = frame_index;
  st.lio_ms = float(f.lio.lio_ms);
  st.vio_ms = float(f.vio_ms);
  st.map_ms = float(f.lio.map_ms + f.map.ms);
  st.map_wait_ms = float(f.link.wait_ms);
  st.total_ms = float(f.total_ms);
  st.sigma_min = float(std::max(0.0, f.lio.sigma_min));
  st.degenerate = f.degenerate;
  st.visual_used = f.visual_used;
  st.map_timeout = f.link.map_timeout;
  st.lidar_failed = f.lidarFailed();
  st.n_points = f.lio.n_points;
  st.n_planes_matched = f.lio.n_matched;
  st.n_visual_points = f.n_visual_points;
  st.n_longterm_visual_points = f.n_longterm_visual_points;
  st.has_time_offset = f.has_time_offset;
  st.time_offset_s = f.time_offset_s;
  st.time_offset_sigma_s = f.time_offset_sigma_s;
  st.dropped_points = std::int32_t(std::min<std::size_t>(dropped_points, 0x7fffffff));
  st.health = std::int8_t(f.health.state);
  st.health_reason = f.health.reason;
  return st;
}

void applyStats(FrameRecord& rec, const EstimatorStats& s) {
  rec.lio_ms = s.lio_ms;
  rec.vio_ms = s.vio_ms;
  rec.map_ms = s.map_ms;
  rec.map_wait_ms = s.map_wait_ms;
  rec.total_ms = s.total_ms;
  rec.sigma_min = s.sigma_min;
  rec.degenerate = s.degenerate;
  rec.visual_used = s.visual_used;
  rec.lidar_failed = s.lidar_failed;
  rec.n_points = s.n_points;
  rec.n_planes_matched = s.n_planes_matched;
  rec.n_visual_points = s.n_visual_points;
  rec.n_longterm_visual_points = s.n_longterm_visual_points;
  rec.has_time_offset = s.has_time_offset;
  rec.time_offset_s = s.time_offset_s;
  rec.time_offset_sigma_s = s.time_offset_sigma_s;
  rec.health = static_cast<HealthState>(s.health);  // 0..3: fromMsg checked it
  rec.health_reason = s.health_reason;
}

}  // namespace livo
