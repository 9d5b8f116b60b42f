// KITTI-style binary LiDAR scans (little-endian float32 records) to LIVO_LIDAR messages.
//
// Layouts (DIR):
//   flat:  DIR/*.bin sorted by name, e.g. kitti_00/000000.bin. Files named <times_prefix><id>.bin hold
//          per-point times (float32 seconds within the sweep) for the scan file whose name ends in <id>
//          (newer_06: raw_00.bin + times_00.bin). When the folder holds several scan series (raw_*,
//          deskewed_*), choose one with `prefix`.
//   dump:  DIR/<sub>/points.bin for every subfolder, sorted by name (optional DIR/<sub>/times.bin).
//   file:  DIR is one .bin file.
// Point records are x,y,z (12 bytes) or x,y,z,intensity (16 bytes). Auto-detection keeps the record sizes
// that divide every file (and match every times file's count); it fails when both or none remain.
// Scan i gets utime = start_time + i / rate; points keep the file order, ring = -1.
#pragma once

#include "livo/common/types.hpp"
#include "livo/datasets/conversion.hpp"

#include <string>
#include <vector>

namespace livo {

enum class PointFields { Auto, Xyz, Xyzi };
enum class SynthTimes { None, Azimuth };

/// Bytes per point record (0 for Auto).
int recordBytes(PointFields f);
const char* toString(PointFields f);

struct KittiOptions {
  std::string lidar_channel = "LIVO_LIDAR";
  std::string sensor = "generic";       ///< lidar_scan_t.sensor
  PointFields fields = PointFields::Auto;
  double rate_hz = 10.0;                ///< Hz, scan i starts at start_time_s + i / rate_hz
  double start_time_s = 0.0;            ///< s, sensor time of the first scan
  std::string prefix;                   ///< flat layout: only scan files whose name starts with this
  std::string times_prefix = "times_";  ///< flat layout: per-point time files <times_prefix><id>.bin
  bool use_times = true;                ///< read per-point time files when present
  /// Offsets when a scan has no time file: None -> 0, Azimuth -> from the azimuth (spinning sensors).
  SynthTimes synth_times = SynthTimes::None;
  ProgressFn progress;                  ///< called per written scan
};

/// One scan to convert.
struct KittiScanFile {
  std::string points_path;
  std::string times_path;  ///< empty when the scan has no per-point times
};

/// The scans of DIR in order (layouts above). Throws DatasetError for a missing folder, no scans, several
/// scan series without a prefix, or time files present for some scans only.
std::vector<KittiScanFile> listKittiScans(const std::string& dir, const KittiOptions& opt = {});

/// Record layout for all files: the requested one (checked against every file size) or the detected one.
PointFields resolvePointFields(const std::vector<KittiScanFile>& scans, PointFields requested);

/// Reads one scan (and its times file when `times_path` is set); sizes are checked before allocating.
LidarScan readKittiScan(const KittiScanFile& file, PointFields fields, Utime utime, const std::string& sensor);

/// Per-point times of a times file (float32 seconds, finite, 0..10 s); `expected_points` must match.
std::vector<float> readTimesFile(const std::string& path, std::size_t expected_points);

/// Offsets of a spinning sensor from the azimuth: t_i = period * frac(s * (az_i - az_0) / 2 pi), where
/// az = atan2(y, x), az_0 is the first finite point and the spin sign s is the sign of the median wrapped
/// azimuth step between consecutive points (firing order). Non-finite points get 0.
void synthAzimuthTimes(LidarScan& scan, double period_s);

/// Converts the scans of DIR into `out_log`. Nothing is left at `out_log` when it throws.
ConversionSummary convertKitti(const std::string& dir, const std::string& out_log, const KittiOptions& opt = {});

}  // namespace livo
