// The map files of an output directory, built from registered scans (world-frame points of each frame):
//   map.pcd  PCL binary PointXYZRGB: one point per occupied voxel of `map_voxel_m` (the centroid of the
//            points that fell in it), coloured by the mean camera colour of its points where a camera
//            saw them, else gray from the mean intensity;
//   map.bt   OctoMap occupancy tree (binary, maximum likelihood) from the scans' rays: every point is a
//            hit at its end and a miss along the ray from the sensor origin (the IMU position of the
//            frame), at `octomap_resolution_m`.
// No LCM here: livo-exporter and livo-run can share it.
#pragma once

#include "livo/common/config.hpp"
#include "livo/common/types.hpp"

#include <Eigen/Core>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

namespace octomap {
class OcTree;
}

namespace livo {

/// Config section `exporter` (all optional).
struct MapExportConfig {
  double map_voxel_m = 0.1;             ///< leaf of the map.pcd voxel grid, m
  std::int64_t max_map_points = 5'000'000;  ///< voxels of map.pcd; points in new voxels beyond are dropped (counted)
  double intensity_max = 0.0;           ///< gray = 255 * min(1, intensity / intensity_max); 0: the largest voxel mean
  bool octomap_enabled = true;          ///< false: no map.bt
  /// map.bt leaf size, m. Ray casting cost grows steeply with resolution: 5,000-point scans of a
  /// 20 m box take ~17 ms at 0.2 m and ~150 ms at 0.1 m (test_process *Speed*).
  double octomap_resolution_m = 0.2;
  double octomap_max_range_m = 30.0;    ///< longer rays are cut here (free space only, no hit), m
  int octomap_every_n = 1;              ///< insert every n-th scan into the OctoMap
  /// Scans waiting for the OctoMap worker thread (the message thread never waits for ray casting);
  /// when full, the oldest waiting scan is dropped (counted). 0: insert in the caller's thread.
  int octomap_queue_scans = 8;
  /// The OctoMap's memory, MB (its nodes with malloc's overhead, checked whenever the tree grew by
  /// 5 %): at the cap the tree stops growing and later scans are left out of map.bt (counted;
  /// map.pcd keeps them). Free space dominates the tree (outdoors at 0.2 m it fills within a few dozen
  /// scans; config/README.md). 0: no cap.
  double octomap_max_mb = 512.0;

  /// Reads the keys above from the `exporter` section; throws ConfigError naming the key.
  void load(const ConfigNode& exporter);
  /// Throws std::invalid_argument naming the field.
  void validate() const;
};

/// Voxel-grid accumulation of coloured points for map.pcd.
class MapCloud {
 public:
  explicit MapCloud(const MapExportConfig& cfg);

  /// rgb: empty, or one 0xRRGGBB per point (-1: not seen by a camera). Non-finite points are skipped.
  void add(const std::vector<Eigen::Vector3f>& p_world, const std::vector<float>& intensity,
           const std::vector<std::int32_t>& rgb);
  std::size_t size() const { return voxels_.size(); }
  std::uint64_t pointsAdded() const { return added_; }
  std::uint64_t pointsDropped() const { return dropped_; }  ///< by max_map_points
  std::uint64_t voxelsColored() const;

  /// Writes a binary PCD of PointXYZRGB (temporary file + rename). Throws std::runtime_error naming
  /// the path on failure. An empty map gives a valid file with 0 points.
  void writePcd(const std::string& path) const;

 private:
  struct Voxel {
    float x = 0, y = 0, z = 0, intensity = 0;  // running means
    float r = 0, g = 0, b = 0;                 // running mean of the coloured points
    std::uint32_t n = 0, n_colored = 0;
  };
  MapExportConfig cfg_;
  std::unordered_map<std::uint64_t, Voxel> voxels_;
  std::uint64_t added_ = 0, dropped_ = 0;
};

/// OctoMap occupancy from scan rays for map.bt, built by a worker thread (octomap_queue_scans > 0).
class OccupancyMap {
 public:
  explicit OccupancyMap(const MapExportConfig& cfg);
  ~OccupancyMap();
  OccupancyMap(const OccupancyMap&) = delete;
  OccupancyMap& operator=(const OccupancyMap&) = delete;

  /// Queues (or, without a queue, inserts) the rays from `p_world_sensor` to each point; every n-th
  /// call only (octomap_every_n).
  void insertScan(const Eigen::Vector3d& p_world_sensor, const std::vector<Eigen::Vector3f>& p_world);
  /// Blocks until every queued scan is in the tree.
  void waitIdle();
  std::uint64_t scansInserted() const { return inserted_; }
  std::uint64_t scansDropped() const { return dropped_; }  ///< by a full queue
  /// Scans left out because the tree reached octomap_max_mb, and the scan count at which it did (0: not reached).
  std::uint64_t scansCapped() const { return capped_scans_; }
  std::uint64_t cappedAtScan() const { return capped_ ? inserted_.load() : 0; }
  /// Empty until the cap was reached; then what map.bt leaves out, for stats.json notes and summaries.
  std::string capNote() const;
  /// The tree's memory as the cap counts it, bytes (walks the tree: waits for the queue first).
  double memoryBytes() {
    waitIdle();
    return treeBytes();
  }
  /// Leaves of the tree (waits for the queue first).
  std::size_t leafCount();
  /// Writes the binary (maximum-likelihood) tree after waitIdle(). Throws std::runtime_error naming
  /// the path.
  void writeBt(const std::string& path);
  /// The tree (waits for the queue first).
  const octomap::OcTree& tree();

 private:
  struct Job {
    Eigen::Vector3d origin;
    std::vector<Eigen::Vector3f> points;
  };
  void insertNow(const Job& job);
  void workerLoop();
  double treeBytes() const;

  MapExportConfig cfg_;
  std::unique_ptr<octomap::OcTree> tree_;
  std::uint64_t calls_ = 0;
  std::atomic<std::uint64_t> inserted_{0}, dropped_{0}, capped_scans_{0};
  std::atomic<bool> capped_{false};
  std::size_t next_check_nodes_ = 0;  ///< tree size at which the cap is checked next (worker only)
  // Worker: jobs_ and busy_ under mutex_; the tree belongs to the worker while it runs a job.
  std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::deque<Job> jobs_;
  bool busy_ = false, quit_ = false;
  std::thread worker_;
};

}  // namespace livo
