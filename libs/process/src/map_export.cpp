#include "livo/process/map_export.hpp"

#include <octomap/OcTree.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fcntl.h>
#include <unistd.h>

namespace livo {

void MapExportConfig::load(const ConfigNode& n) {
  n.get("map_voxel_m", map_voxel_m).get("max_map_points", max_map_points).get("intensity_max", intensity_max);
  n.get("octomap_enabled", octomap_enabled).get("octomap_resolution_m", octomap_resolution_m);
  n.get("octomap_max_range_m", octomap_max_range_m).get("octomap_every_n", octomap_every_n);
  n.get("octomap_queue_scans", octomap_queue_scans).get("octomap_max_mb", octomap_max_mb);
  n.check(map_voxel_m > 0.0, "map_voxel_m", "must be > 0 m");
  n.check(max_map_points > 0, "max_map_points", "must be > 0");
  n.check(intensity_max >= 0.0, "intensity_max", "must be >= 0 (0: automatic)");
  n.check(octomap_resolution_m > 0.0, "octomap_resolution_m", "must be > 0 m");
  n.check(octomap_max_range_m > 0.0, "octomap_max_range_m", "must be > 0 m");
  n.check(octomap_every_n >= 1, "octomap_every_n", "must be >= 1");
  n.check(octomap_queue_scans >= 0, "octomap_queue_scans", "must be >= 0 (0: no worker thread)");
  n.check(octomap_max_mb >= 0.0, "octomap_max_mb", "must be >= 0 MB (0: no cap)");
}

void MapExportConfig::validate() const {
  auto need = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("MapExportConfig.") + what);
  };
  need(std::isfinite(map_voxel_m) && map_voxel_m > 0.0, "map_voxel_m must be > 0");
  need(max_map_points > 0, "max_map_points must be > 0");
  need(std::isfinite(intensity_max) && intensity_max >= 0.0, "intensity_max must be >= 0");
  need(std::isfinite(octomap_resolution_m) && octomap_resolution_m > 0.0, "octomap_resolution_m must be > 0");
  need(std::isfinite(octomap_max_range_m) && octomap_max_range_m > 0.0, "octomap_max_range_m must be > 0");
  need(octomap_every_n >= 1, "octomap_every_n must be >= 1");
  need(octomap_queue_scans >= 0, "octomap_queue_scans must be >= 0");
  need(std::isfinite(octomap_max_mb) && octomap_max_mb >= 0.0, "octomap_max_mb must be >= 0");
}

// ---------------------------------------------------------------- map.pcd

namespace {

constexpr std::int64_t kKeyBits = 21;
constexpr std::int64_t kKeyHalf = std::int64_t(1) << (kKeyBits - 1);

/// Packs the voxel index of p into 3 x 21 bits; false when p lies outside the key range
/// (+-2^20 voxels, about +-100 km at 0.1 m).
bool voxelKey(const Eigen::Vector3f& p, double leaf, std::uint64_t& key) {
  std::uint64_t k = 0;
  for (int a = 0; a < 3; ++a) {
    const double i = std::floor(double(p[a]) / leaf);
    if (!(i >= -double(kKeyHalf) && i < double(kKeyHalf))) return false;
    k = (k << kKeyBits) | std::uint64_t(std::int64_t(i) + kKeyHalf);
  }
  key = k;
  return true;
}

void renameOrThrow(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(path + ": cannot replace with " + tmp + ": " + ec.message());
}

}  // namespace

MapCloud::MapCloud(const MapExportConfig& cfg) : cfg_(cfg) { cfg_.validate(); }

void MapCloud::add(const std::vector<Eigen::Vector3f>& p_world, const std::vector<float>& intensity,
                   const std::vector<std::int32_t>& rgb) {
  const bool colored = !rgb.empty();
  if (intensity.size() != p_world.size() || (colored && rgb.size() != p_world.size()))
    throw std::invalid_argument("MapCloud::add: intensity / rgb sizes differ from the points");
  for (std::size_t i = 0; i < p_world.size(); ++i) {
    const Eigen::Vector3f& p = p_world[i];
    std::uint64_t key = 0;
    if (!p.allFinite() || !voxelKey(p, cfg_.map_voxel_m, key)) {
      ++dropped_;
      continue;
    }
    auto it = voxels_.find(key);
    if (it == voxels_.end()) {
      if (std::int64_t(voxels_.size()) >= cfg_.max_map_points) {
        ++dropped_;
        continue;
      }
      it = voxels_.emplace(key, Voxel{}).first;
    }
    Voxel& v = it->second;
    ++added_;
    ++v.n;
    const float w = 1.0f / float(v.n);  // running means: m += (x - m) / n
    v.x += (p.x() - v.x) * w;
    v.y += (p.y() - v.y) * w;
    v.z += (p.z() - v.z) * w;
    const float in = std::isfinite(intensity[i]) ? intensity[i] : 0.0f;
    v.intensity += (in - v.intensity) * w;
    if (colored && rgb[i] >= 0) {
      ++v.n_colored;
      const float wc = 1.0f / float(v.n_colored);
      v.r += (float((rgb[i] >> 16) & 0xFF) - v.r) * wc;
      v.g += (float((rgb[i] >> 8) & 0xFF) - v.g) * wc;
      v.b += (float(rgb[i] & 0xFF) - v.b) * wc;
    }
  }
}

std::uint64_t MapCloud::voxelsColored() const {
  std::uint64_t n = 0;
  for (const auto& [k, v] : voxels_) n += v.n_colored > 0;
  return n;
}

void MapCloud::writePcd(const std::string& path) const {
  double imax = cfg_.intensity_max;
  if (imax <= 0.0)
    for (const auto& [k, v] : voxels_) imax = std::max(imax, double(v.intensity));
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  cloud.reserve(voxels_.size());
  auto to8 = [](double x) { return std::uint8_t(std::lround(std::clamp(x, 0.0, 255.0))); };
  for (const auto& [k, v] : voxels_) {
    pcl::PointXYZRGB q;
    q.x = v.x;
    q.y = v.y;
    q.z = v.z;
    if (v.n_colored > 0) {
      q.r = to8(v.r);
      q.g = to8(v.g);
      q.b = to8(v.b);
    } else {
      const std::uint8_t gray = imax > 0.0 ? to8(255.0 * double(v.intensity) / imax) : 128;
      q.r = q.g = q.b = gray;
    }
    cloud.push_back(q);
  }
  cloud.width = static_cast<std::uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
  const std::string tmp = path + ".tmp";
  if (cloud.empty()) {
    // PCL refuses to write an empty cloud; an empty map is still a valid (0-point) PCD file.
    std::ofstream os(tmp);
    os << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\n"
          "TYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 0\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\nDATA ascii\n";
    if (!os) throw std::runtime_error(tmp + ": cannot write");
  } else if (pcl::io::savePCDFileBinary(tmp, cloud) != 0) {
    throw std::runtime_error(tmp + ": PCL could not write the map cloud");
  }
  renameOrThrow(tmp, path);
}

// ---------------------------------------------------------------- map.bt

OccupancyMap::OccupancyMap(const MapExportConfig& cfg)
    : cfg_(cfg), tree_(std::make_unique<octomap::OcTree>(cfg.octomap_resolution_m)) {
  cfg_.validate();
  if (cfg_.octomap_queue_scans > 0) worker_ = std::thread([this] { workerLoop(); });
}

OccupancyMap::~OccupancyMap() {
  if (worker_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    wake_.notify_all();
    worker_.join();
  }
}

void OccupancyMap::insertScan(const Eigen::Vector3d& p_world_sensor, const std::vector<Eigen::Vector3f>& p_world) {
  if ((calls_++ % std::uint64_t(cfg_.octomap_every_n)) != 0) return;
  if (!p_world_sensor.allFinite()) return;
  if (capped_) {  // no copy into the queue for a scan the tree will not take
    ++capped_scans_;
    return;
  }
  if (!worker_.joinable()) {
    insertNow(Job{p_world_sensor, p_world});
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (jobs_.size() >= std::size_t(cfg_.octomap_queue_scans)) {  // the worker is behind: drop the oldest
      jobs_.pop_front();
      ++dropped_;
    }
    jobs_.push_back(Job{p_world_sensor, p_world});
  }
  wake_.notify_one();
}

double OccupancyMap::treeBytes() const {
  // OcTree::memoryUsage() counts the nodes and the inner nodes' child arrays, not malloc's chunk
  // overhead: a 16-byte node takes a 32-byte chunk, an inner node's 64-byte array an 80-byte one.
  const double leaves = double(tree_->getNumLeafNodes()), all = double(tree_->size());
  return all * 32.0 + (all - leaves) * 80.0;
}

std::string OccupancyMap::capNote() const {
  if (!capped_) return "";
  std::ostringstream os;
  os << "map.bt stopped growing at exporter.octomap_max_mb (" << cfg_.octomap_max_mb << " MB) after scan "
     << inserted_.load() << "; " << capped_scans_.load() << " later scans are not in it (map.pcd has them)";
  return os.str();
}

void OccupancyMap::insertNow(const Job& job) {
  if (capped_) {
    ++capped_scans_;
    return;
  }
  octomap::Pointcloud cloud;
  cloud.reserve(job.points.size());
  for (const auto& p : job.points)
    if (p.allFinite()) cloud.push_back(p.x(), p.y(), p.z());
  const octomap::point3d origin(float(job.origin.x()), float(job.origin.y()), float(job.origin.z()));
  // discretize: one ray per end voxel (the scans are already downsampled; this removes duplicates).
  tree_->insertPointCloud(cloud, origin, cfg_.octomap_max_range_m, /*lazy_eval=*/false, /*discretize=*/true);
  ++inserted_;
  // The memory cap: counting the leaves walks the tree, so only after the tree grew by 5 %.
  if (cfg_.octomap_max_mb > 0.0 && tree_->size() >= next_check_nodes_) {
    const double bytes = treeBytes();
    if (bytes > cfg_.octomap_max_mb * 1024.0 * 1024.0) capped_ = true;  // inserted_ stays the scan it stopped at
    next_check_nodes_ = tree_->size() + tree_->size() / 20 + 1;
  }
}

void OccupancyMap::workerLoop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return quit_ || !jobs_.empty(); });
    if (jobs_.empty()) return;  // quit_ and nothing left
    Job job = std::move(jobs_.front());
    jobs_.pop_front();
    busy_ = true;
    lock.unlock();
    insertNow(job);
    lock.lock();
    busy_ = false;
    if (jobs_.empty()) idle_.notify_all();
  }
}

void OccupancyMap::waitIdle() {
  if (!worker_.joinable()) return;
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return jobs_.empty() && !busy_; });
}

std::size_t OccupancyMap::leafCount() {
  waitIdle();
  return tree_->getNumLeafNodes();
}

const octomap::OcTree& OccupancyMap::tree() {
  waitIdle();
  return *tree_;
}

void OccupancyMap::writeBt(const std::string& path) {
  waitIdle();
  const std::string tmp = path + ".tmp";
  // Debian's OctoMap is built with debug output: it prints "Writing N nodes ... done." with fprintf on
  // stderr. Keep that out of the processes' logs (nothing else prints here: the worker is idle).
  struct SilenceStderr {
    int saved = -1;
    SilenceStderr() {
      std::fflush(stderr);
      saved = ::dup(STDERR_FILENO);
      const int null_fd = ::open("/dev/null", O_WRONLY);
      if (null_fd >= 0) {
        ::dup2(null_fd, STDERR_FILENO);
        ::close(null_fd);
      }
    }
    ~SilenceStderr() {
      std::fflush(stderr);
      if (saved >= 0) {
        ::dup2(saved, STDERR_FILENO);
        ::close(saved);
      }
    }
  };
  bool ok = false;
  {
    SilenceStderr quiet;
    ok = tree_->writeBinary(tmp);
  }
  if (!ok) throw std::runtime_error(tmp + ": OctoMap could not write the tree");
  renameOrThrow(tmp, path);
}

}  // namespace livo
