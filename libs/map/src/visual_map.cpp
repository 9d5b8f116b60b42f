// VisualMap: storage, retrieval (docs/algorithms.md 4.2), creation (5.1) and housekeeping. The observation
// rules, reference selection and outlier handling are in visual_map_observations.cpp.
#include "livo/map/visual_map.hpp"

#include "livo/map/visual_map_scores.hpp"
#include "livo/sensors/camera_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace livo {

namespace {

constexpr std::size_t kHeapOverhead = 16;  // glibc: 8-byte header, 16-byte rounding (as VoxelMap::bytes)
// |p / s| below 2^52 keeps floor() exact and the key far from int64 overflow (as VoxelMap).
constexpr double kMaxScaled = 4503599627370496.0;

bool keyable(const Vec3& p, double voxel_size) {
  return p.allFinite() && (p.cwiseAbs() / voxel_size).maxCoeff() < kMaxScaled;
}

void checkGray(const Image& gray, const CameraModel& cam, const char* who) {
  if (gray.format != PixelFormat::Gray8)
    throw std::invalid_argument(std::string(who) + ": image must be Gray8, got " + toString(gray.format));
  if (gray.width != cam.width() || gray.height != cam.height())
    throw std::invalid_argument(std::string(who) + ": image " + std::to_string(gray.width) + "x" +
                                std::to_string(gray.height) + " does not match the camera " +
                                std::to_string(cam.width()) + "x" + std::to_string(cam.height()));
  if (gray.row_stride < gray.width || gray.height <= 0 ||
      gray.data.size() < std::size_t(gray.row_stride) * std::size_t(gray.height - 1) + std::size_t(gray.width))
    throw std::invalid_argument(std::string(who) + ": image buffer smaller than row_stride x height");
}

}  // namespace

ImageGrid::ImageGrid(int width, int height, int cell)
    : cell_px(cell), cols(cell > 0 ? (width + cell - 1) / cell : 0), rows(cell > 0 ? (height + cell - 1) / cell : 0) {}

int ImageGrid::cellOf(const Vec2& px) const {
  if (!(px.x() >= 0.0 && px.y() >= 0.0)) return -1;
  const int c = static_cast<int>(px.x() / cell_px), r = static_cast<int>(px.y() / cell_px);
  if (c >= cols || r >= rows) return -1;
  return r * cols + c;
}

VisualMap::VisualMap(VisualMapConfig config, bool longterm) : config_(std::move(config)), longterm_(longterm) {
  config_.validate();
}
VisualMap::~VisualMap() = default;
VisualMap::VisualMap(VisualMap&&) noexcept = default;
VisualMap& VisualMap::operator=(VisualMap&&) noexcept = default;

ImageGrid selectionGrid(const CameraModel& cam, int cell_px) { return ImageGrid(cam.width(), cam.height(), cell_px); }

// Step 1 of retrieve: the visual voxels touched by the scan (floor keys: no off-by-one for negative
// coordinates), or the given keys. Only voxels that exist in the visual hash are collected, then
// deduplicated (sort + unique).
std::size_t VisualMap::collectSearchedVoxels(const std::vector<Vec3>& scan_points_world,
                                             const std::vector<VoxelKey>* voxel_keys) {
  searched_.clear();
  if (voxel_keys != nullptr) {
    for (const VoxelKey& k : *voxel_keys) {
      const auto it = voxels_.find(k);
      if (it != voxels_.end()) searched_.push_back(&it->second);
    }
  } else {
    VoxelKey last;
    bool have_last = false;
    for (const Vec3& p : scan_points_world) {
      if (!keyable(p, config_.voxel_size_m)) continue;
      const VoxelKey k = keyOf(p);
      if (have_last && k == last) continue;  // consecutive scan points mostly share a voxel
      last = k;
      have_last = true;
      const auto it = voxels_.find(k);
      if (it != voxels_.end()) searched_.push_back(&it->second);
    }
  }
  std::sort(searched_.begin(), searched_.end());
  searched_.erase(std::unique(searched_.begin(), searched_.end()), searched_.end());
  return searched_.size();
}

// Step 3 of retrieve: the scan's sparse depth image (smallest depth per pixel) in depth_.
void VisualMap::rasterDepth(const CameraModel& cam, const Pose& T_camera_world, const std::vector<Vec3>& scan_points_world) {
  const int w = cam.width(), h = cam.height();
  if (depth_.size() != std::size_t(w) * std::size_t(h)) depth_.assign(std::size_t(w) * std::size_t(h), 0.f);
  for (const Vec3& p : scan_points_world) {
    if (!p.allFinite()) continue;
    const Vec3 p_cam = T_camera_world * p;
    if (!(p_cam.z() > 0.0)) continue;
    Vec2 px;
    if (!cam.project(p_cam, px)) continue;
    const double ux = std::round(px.x()), uy = std::round(px.y());
    if (!(ux >= 0.0 && uy >= 0.0 && ux < w && uy < h)) continue;
    const std::size_t idx = std::size_t(uy) * std::size_t(w) + std::size_t(ux);
    const float z = static_cast<float>(p_cam.z());
    if (depth_[idx] == 0.f) {
      depth_touched_.push_back(int(idx));
      depth_[idx] = z;
    } else if (z < depth_[idx]) {
      depth_[idx] = z;
    }
  }
}

bool winsCell(const VisualPoint& p, double z, const VisualPoint* best, double best_z, double same_surface_m) {
  if (best == nullptr) return true;
  if (p.from_longterm != best->from_longterm)
    return p.from_longterm ? z <= best_z + same_surface_m : z < best_z - same_surface_m;
  return z < best_z || (z == best_z && p.id < best->id);
}

VisualRetrieval VisualMap::retrieve(const CameraModel& cam, const Pose& T_world_camera,
                                   const std::vector<Vec3>& scan_points_world, const std::vector<VoxelKey>* voxel_keys) {
  VisualRetrieval got;
  got.grid = selectionGrid(cam, config_.grid_cell_px);
  const ImageGrid& grid = got.grid;
  got.occupied.assign(std::size_t(grid.size()), false);
  VisualRetrievalStats& stats = got.stats;
  const Pose T_camera_world = T_world_camera.inverse();

  stats.visual_voxels = collectSearchedVoxels(scan_points_world, voxel_keys);

  // 2. Per grid cell, the qualifying point with the smallest depth.
  struct Best {
    double z = std::numeric_limits<double>::infinity();
    VisualPoint* point = nullptr;
    Vec2 px = Vec2::Zero();
  };
  std::vector<Best> best(std::size_t(grid.size()));
  for (const std::vector<VisualPoint*>* voxel : searched_) {
    for (VisualPoint* p : *voxel) {
      ++stats.searched_points;
      if (p->referenceObs() == nullptr) continue;
      const Vec3 p_cam = T_camera_world * p->p_world;
      if (!(p_cam.z() >= config_.min_depth_m)) continue;
      Vec2 px;
      if (!cam.project(p_cam, px) || !cam.inImage(px, config_.border_px)) continue;
      const int cell = grid.cellOf(px);
      if (cell < 0) continue;
      ++stats.in_image;
      Best& b = best[std::size_t(cell)];
      if (winsCell(*p, p_cam.z(), b.point, b.z, config_.occlusion_depth_m)) b = {p_cam.z(), p, px};
    }
  }

  // 3. Sparse depth image of the scan (smallest depth per pixel), only when a candidate needs it.
  const int w = cam.width(), h = cam.height();
  const bool any = std::any_of(best.begin(), best.end(), [](const Best& b) { return b.point != nullptr; });
  if (any) rasterDepth(cam, T_camera_world, scan_points_world);

  // 4. Occlusion: a scan point within +-window px closer by more than occlusion_depth_m.
  const int win = config_.occlusion_window_px;
  for (std::size_t cell = 0; cell < best.size(); ++cell) {
    const Best& b = best[cell];
    if (b.point == nullptr) continue;
    const int ux = int(std::lround(b.px.x())), uy = int(std::lround(b.px.y()));
    const float limit = static_cast<float>(b.z - config_.occlusion_depth_m);
    bool occluded = false;
    for (int y = std::max(0, uy - win); y <= std::min(h - 1, uy + win) && !occluded; ++y) {
      const float* row = depth_.data() + std::size_t(y) * std::size_t(w);
      for (int x = std::max(0, ux - win); x <= std::min(w - 1, ux + win); ++x) {
        if (row[x] > 0.f && row[x] < limit) {
          occluded = true;
          break;
        }
      }
    }
    if (occluded) {
      ++stats.occluded;
      continue;
    }
    got.occupied[cell] = true;
    got.points.push_back(b.point);
    got.pixels.push_back(b.px);
  }
  for (int idx : depth_touched_) depth_[std::size_t(idx)] = 0.f;
  depth_touched_.clear();
  stats.selected = got.points.size();
  got.longterm = longterm_ ? got.points.size() : 0;
  return got;
}

int VisualMap::addPoints(const Image& gray, const CameraModel& cam, const Pose& T_world_camera, float inv_exposure,
                         Utime t, const std::vector<NewPointCandidate>& candidates,
                         const std::vector<bool>& occupied_cells) {
  checkGray(gray, cam, "VisualMap::addPoints");
  const ImageGrid grid = selectionGrid(cam, config_.grid_cell_px);
  if (!occupied_cells.empty() && occupied_cells.size() != std::size_t(grid.size()))
    throw std::invalid_argument("VisualMap::addPoints: occupied_cells has " + std::to_string(occupied_cells.size()) +
                                " entries, the grid has " + std::to_string(grid.size()));
  const Pose T_camera_world = T_world_camera.inverse();
  const Vec3 camera_center = T_world_camera.translation();

  // Best Shi-Tomasi candidate per free cell (docs/algorithms.md 5.1).
  struct Pick {
    double score = -1.0;
    int index = -1;
    Vec2 px = Vec2::Zero();
  };
  std::vector<Pick> picks(std::size_t(grid.size()));
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const NewPointCandidate& c = candidates[i];
    if (!keyable(c.p_world, config_.voxel_size_m) || !c.cov_world.allFinite()) continue;
    const Vec3 p_cam = T_camera_world * c.p_world;
    if (!(p_cam.z() >= config_.min_depth_m)) continue;  // in front of the camera (fix of #421)
    Vec2 px;
    if (!cam.project(p_cam, px) || !cam.inImage(px, config_.border_px)) continue;
    const int cell = grid.cellOf(px);
    if (cell < 0 || (!occupied_cells.empty() && occupied_cells[std::size_t(cell)])) continue;
    const double score = shiTomasiScore(gray, px);
    if (!(score > config_.min_shi_tomasi)) continue;
    Pick& pick = picks[std::size_t(cell)];
    if (score > pick.score) pick = {score, int(i), px};
  }

  int created = 0;
  for (const Pick& pick : picks) {
    if (pick.index < 0) continue;
    const NewPointCandidate& c = candidates[std::size_t(pick.index)];
    auto point = std::make_unique<VisualPoint>();
    VisualObservation o;
    if (!extractPatchPyramid(gray, pick.px, o.patch)) continue;  // cannot happen inside the border
    o.utime = t;
    o.T_world_camera = T_world_camera;
    o.px = pick.px;
    o.inv_exposure = inv_exposure;
    const Vec3 to_camera = camera_center - c.p_world;
    Vec3 n = c.normal_world;
    const double norm = n.norm();
    n = (std::isfinite(norm) && norm > 1e-9) ? Vec3(n / norm) : Vec3(to_camera.normalized());
    if (n.dot(to_camera) < 0.0) n = -n;  // face the camera
    point->id = next_id_++;
    point->p_world = c.p_world;
    point->normal = n;
    point->cov = c.cov_world;
    point->obs.reserve(1);
    point->obs.push_back(o);
    point->views = 1;
    point->reference = 0;
    point->last_seen = t;
    VisualPoint* raw = point.get();
    by_id_.emplace(raw->id, std::move(point));
    index(raw);
    ++created;
  }
  return created;
}

void VisualMap::index(VisualPoint* p) { voxels_[keyOf(p->p_world)].push_back(p); }

void VisualMap::unindex(const VisualPoint* p) {
  const auto it = voxels_.find(keyOf(p->p_world));
  if (it == voxels_.end()) return;
  auto& list = it->second;
  const auto pos = std::find(list.begin(), list.end(), p);
  if (pos != list.end()) {
    *pos = list.back();
    list.pop_back();
  }
  if (list.empty()) voxels_.erase(it);
}

std::size_t VisualMap::bytes() const {
  std::size_t b = 0;
  // Hash tables: one pointer per bucket; a node holds the next pointer and the key/value pair
  // (libstdc++ caches no hash code for these fast, noexcept hashes).
  b += by_id_.bucket_count() * sizeof(void*);
  b += by_id_.size() * (sizeof(void*) + sizeof(std::pair<const std::int64_t, std::unique_ptr<VisualPoint>>) + kHeapOverhead);
  b += voxels_.bucket_count() * sizeof(void*);
  b += voxels_.size() * (sizeof(void*) + sizeof(std::pair<const VoxelKey, std::vector<VisualPoint*>>) + kHeapOverhead);
  for (const auto& kv : voxels_)
    if (kv.second.capacity() > 0) b += kv.second.capacity() * sizeof(VisualPoint*) + kHeapOverhead;
  for (const auto& kv : by_id_) {
    const VisualPoint& p = *kv.second;
    b += sizeof(VisualPoint) + kHeapOverhead;
    if (p.obs.capacity() > 0) b += p.obs.capacity() * sizeof(VisualObservation) + kHeapOverhead;
  }
  b += suspects_.capacity() * sizeof(std::int64_t);
  return b;
}

std::size_t VisualMap::scratchBytes() const {
  return depth_.capacity() * sizeof(float) + depth_touched_.capacity() * sizeof(int) +
         searched_.capacity() * sizeof(void*);
}

void VisualMap::forEach(const std::function<void(const VisualPoint&)>& f) const {
  for (const auto& kv : by_id_) f(*kv.second);
}

void VisualMap::forEach(const std::function<void(VisualPoint&)>& f) {
  for (auto& kv : by_id_) f(*kv.second);
}

std::vector<std::int64_t> VisualMap::idsOutsideBox(const Vec3& center, double half_edge_m) const {
  std::vector<std::int64_t> ids;
  for (const auto& kv : voxels_) {
    const Vec3 c = kv.first.center(config_.voxel_size_m);
    if (((c - center).cwiseAbs().array() > half_edge_m).any())
      for (const VisualPoint* p : kv.second) ids.push_back(p->id);
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

std::unique_ptr<VisualPoint> VisualMap::extract(std::int64_t id) {
  const auto it = by_id_.find(id);
  if (it == by_id_.end()) return nullptr;
  std::unique_ptr<VisualPoint> p = std::move(it->second);
  by_id_.erase(it);
  unindex(p.get());
  return p;
}

bool VisualMap::insert(std::unique_ptr<VisualPoint> point) {
  if (!point || !keyable(point->p_world, config_.voxel_size_m) || by_id_.count(point->id) > 0) return false;
  next_id_ = std::max(next_id_, point->id + 1);
  point->from_longterm = point->from_longterm || longterm_;
  VisualPoint* raw = point.get();
  by_id_.emplace(raw->id, std::move(point));
  index(raw);
  return true;
}

void VisualMap::forEachInVoxel(const VoxelKey& key, const std::function<void(const VisualPoint&)>& f) const {
  const auto it = voxels_.find(key);
  if (it == voxels_.end()) return;
  for (const VisualPoint* p : it->second) f(*p);
}

VisualPoint* VisualMap::find(std::int64_t id) {
  const auto it = by_id_.find(id);
  return it == by_id_.end() ? nullptr : it->second.get();
}

const VisualPoint* VisualMap::find(std::int64_t id) const {
  const auto it = by_id_.find(id);
  return it == by_id_.end() ? nullptr : it->second.get();
}

void VisualMap::clear() {
  voxels_.clear();
  by_id_.clear();
  suspects_.clear();
}

}  // namespace livo
