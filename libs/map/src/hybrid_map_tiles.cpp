#include "livo/map/hybrid_map_tiles.hpp"

#include <stdexcept>

namespace livo {

namespace {
constexpr std::size_t kHeapOverhead = 16;  // glibc: 8-byte header, 16-byte rounding (as VoxelMap::bytes)

std::int64_t floorDiv(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}
}  // namespace

RootTileIndex::RootTileIndex(double voxel_size_m, int tile_voxels)
    : voxel_size_m_(voxel_size_m), tile_voxels_(tile_voxels) {
  if (!(voxel_size_m > 0.0)) throw std::invalid_argument("RootTileIndex: voxel_size_m must be > 0");
  if (tile_voxels < 1) throw std::invalid_argument("RootTileIndex: tile_voxels must be >= 1");
}

VoxelKey RootTileIndex::tileOf(const VoxelKey& root) const {
  return {floorDiv(root.x, tile_voxels_), floorDiv(root.y, tile_voxels_), floorDiv(root.z, tile_voxels_)};
}

void RootTileIndex::add(const VoxelKey& root) {
  if (have_last_root_ && root == last_root_) return;
  const VoxelKey tile = tileOf(root);
  if (last_set_ == nullptr || tile != last_tile_) {
    last_set_ = &tiles_[tile];  // references into an unordered_map stay valid across rehashes
    last_tile_ = tile;
  }
  if (last_set_->insert(root).second) ++count_;
  last_root_ = root;
  have_last_root_ = true;
}

bool RootTileIndex::remove(const VoxelKey& root) {
  const VoxelKey tile = tileOf(root);
  const auto it = tiles_.find(tile);
  if (it == tiles_.end() || it->second.erase(root) == 0) return false;
  --count_;
  have_last_root_ = false;  // the cached root may be the one just removed
  if (it->second.empty()) {
    if (last_set_ == &it->second) last_set_ = nullptr;
    tiles_.erase(it);
  }
  return true;
}

void RootTileIndex::clear() {
  tiles_.clear();
  count_ = 0;
  have_last_root_ = false;
  last_set_ = nullptr;
}

std::vector<VoxelKey> RootTileIndex::tilesReachingOutside(const Vec3& center, double half_edge_m) const {
  std::vector<VoxelKey> out;
  const double s = voxel_size_m_;
  const double n = double(tile_voxels_);
  for (const auto& kv : tiles_) {
    const VoxelKey& t = kv.first;
    // Root centres of the tile span [(t n + 0.5) s, (t n + n - 0.5) s] per axis.
    const std::int64_t tk[3] = {t.x, t.y, t.z};
    bool inside = true;
    for (int i = 0; i < 3 && inside; ++i) {
      const double lo = (double(tk[i]) * n + 0.5) * s, hi = (double(tk[i]) * n + n - 0.5) * s;
      inside = lo - center[i] >= -half_edge_m && hi - center[i] <= half_edge_m;
    }
    if (!inside) out.push_back(t);
  }
  return out;
}

RootTileIndex::RootSet* RootTileIndex::roots(const VoxelKey& tile) {
  const auto it = tiles_.find(tile);
  return it == tiles_.end() ? nullptr : &it->second;
}

void RootTileIndex::dropIfEmpty(const VoxelKey& tile) {
  const auto it = tiles_.find(tile);
  if (it == tiles_.end() || !it->second.empty()) return;
  if (last_set_ == &it->second) last_set_ = nullptr;
  have_last_root_ = false;
  tiles_.erase(it);
}

std::size_t RootTileIndex::bytes() const {
  // Outer table: buckets + nodes (next pointer, key, the set object); each set: buckets + nodes
  // (next pointer, key; libstdc++ caches no hash code for this noexcept hash).
  std::size_t b = tiles_.bucket_count() * sizeof(void*);
  b += tiles_.size() * (sizeof(void*) + sizeof(std::pair<const VoxelKey, RootSet>) + kHeapOverhead);
  for (const auto& kv : tiles_) {
    b += kv.second.bucket_count() * sizeof(void*) + kHeapOverhead;
    b += kv.second.size() * (sizeof(void*) + sizeof(VoxelKey) + kHeapOverhead);
  }
  return b;
}

}  // namespace livo
