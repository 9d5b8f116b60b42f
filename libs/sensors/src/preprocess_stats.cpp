#include "livo/sensors/preprocess_stats.hpp"

#include <sstream>

namespace livo {

std::string PreprocessStats::summary() const {
  std::ostringstream s;
  s << "frames " << frames << " (without image " << frames_without_image << ", empty sweeps " << empty_sweeps
    << ", lidar incomplete " << frames_lidar_incomplete << ", imu incomplete " << frames_imu_incomplete << ")\n";
  s << "images in " << images_in << ": used " << images_used << ", dropped " << imagesDropped() << " (ignored "
    << images_ignored << ", invalid " << images_invalid << ", stale " << images_stale << ", out of order "
    << images_out_of_order << ", decimated " << images_decimated << ", too close " << images_too_close
    << ", no lidar " << images_no_lidar << ", overflow " << images_overflow << ", glitches " << images_glitches << ")\n";
  s << "imu in " << imu_in << ": invalid " << imu_invalid << ", out of order " << imu_out_of_order
    << ", duplicates " << imu_duplicates << ", gaps " << imu_gaps << " (largest " << imu_max_gap_s
    << " s), overflow " << imu_overflow << ", glitches " << imu_glitches << "\n";
  s << "scans in " << scans_in << ": out of order " << scans_out_of_order << ", empty " << scans_empty
    << ", glitches " << scans_glitches << "; confirmed forward jumps (all streams) " << forward_jumps << "\n";
  s << "points in " << points_in << ": emitted " << points_emitted << ", nan " << points_nan << ", bad time "
    << points_bad_time << ", blind " << points_blind << ", range " << points_range << ", decimated "
    << points_decimated << ", out of order " << points_out_of_order << ", late " << points_late << ", overflow "
    << points_overflow << ", voxel merged " << points_voxel_merged << "\n";
  return s.str();
}

}  // namespace livo
