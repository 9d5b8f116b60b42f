#include "livo/loop/site_map.hpp"

#include "livo/loop/loop_closer.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace livo {

namespace {

constexpr char kSiteMagic[8] = {'L', 'I', 'V', 'O', 'S', 'I', 'T', 'E'};
constexpr char kTileMagic[8] = {'L', 'I', 'V', 'O', 'T', 'I', 'L', 'E'};
constexpr std::uint32_t kVersion = 1, kByteOrder = 0x01020304;
constexpr std::size_t kPointBytes = 3 * sizeof(std::int16_t);

template <class T>
void put(std::ofstream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof v);
}

std::string tilePath(const std::string& dir, std::int32_t x, std::int32_t y) {
  return dir + "/tiles/tile_" + std::to_string(x) + "_" + std::to_string(y) + ".bin";
}

/// Reads from a file, naming it and what was read on failure.
class Reader {
 public:
  explicit Reader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw std::runtime_error("site map " + path + ": cannot open (not a site map directory?)");
    in_.seekg(0, std::ios::end);
    size_ = static_cast<std::uint64_t>(in_.tellg());
    in_.seekg(0);
  }
  template <class T>
  T get(const char* what) {
    T v{};
    in_.read(reinterpret_cast<char*>(&v), sizeof v);
    if (!in_) fail(std::string("file ends in ") + what);
    return v;
  }
  void bytes(void* dst, std::size_t n, const char* what) {
    in_.read(static_cast<char*>(dst), static_cast<std::streamsize>(n));
    if (!in_) fail(std::string("file ends in ") + what);
  }
  std::uint64_t remaining() { return size_ - static_cast<std::uint64_t>(in_.tellg()); }
  [[noreturn]] void fail(const std::string& why) const { throw std::runtime_error("site map " + path_ + ": " + why); }

 private:
  std::string path_;
  std::ifstream in_;
  std::uint64_t size_ = 0;
};

}  // namespace

void saveSiteMap(const std::string& dir, const LoopCloser& closer, const PlaceDescriptorConfig& descriptor,
                 double tile_m) {
  if (!(tile_m > 0) || !std::isfinite(tile_m)) throw std::invalid_argument("site map: tile edge must be > 0");
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir + "/tiles", ec);
  if (ec) throw std::runtime_error("site map " + dir + ": cannot create the directory: " + ec.message());
  for (const auto& e : fs::directory_iterator(dir + "/tiles"))  // an older site map's tiles
    if (e.path().filename().string().rfind("tile_", 0) == 0) fs::remove(e.path(), ec);

  const PoseGraph& g = closer.graph();
  const int n = static_cast<int>(g.size());
  std::vector<SiteKeyframe> keys(static_cast<std::size_t>(n));
  std::map<std::pair<std::int32_t, std::int32_t>, std::vector<int>> by_tile;
  for (int i = 0; i < n; ++i) {
    SiteKeyframe& k = keys[std::size_t(i)];
    k.utime = closer.places().entry(i).utime;
    k.T_map = g.mapPose(i);
    k.tile_x = static_cast<std::int32_t>(std::floor(k.T_map.translation().x() / tile_m));
    k.tile_y = static_cast<std::int32_t>(std::floor(k.T_map.translation().y() / tile_m));
    by_tile[{k.tile_x, k.tile_y}].push_back(i);
  }
  for (const auto& [key, ids] : by_tile) {
    const std::string path = tilePath(dir, key.first, key.second);
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(kTileMagic, sizeof kTileMagic);
    std::uint64_t offset = 0;
    for (const int i : ids) {
      const PackedPoints pts = closer.keyframePoints(i);
      SiteKeyframe& k = keys[std::size_t(i)];
      k.offset = offset;
      k.count = pts.size();
      k.step = pts.step();
      out.write(reinterpret_cast<const char*>(pts.packed().data()), static_cast<std::streamsize>(pts.size() * kPointBytes));
      offset += pts.size();
    }
    if (!out) throw std::runtime_error("site map " + path + ": write failed (disk full?)");
  }

  const std::string index = dir + "/site.bin", tmp = index + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("site map " + tmp + ": cannot open for writing");
    out.write(kSiteMagic, sizeof kSiteMagic);
    put(out, kVersion);
    put(out, kByteOrder);
    put(out, tile_m);
    put(out, std::int32_t(descriptor.rings));
    put(out, std::int32_t(descriptor.sectors));
    put(out, descriptor.min_range_m);
    put(out, descriptor.max_range_m);
    put(out, descriptor.height_cap_m);
    put(out, std::uint64_t(n));
    for (int i = 0; i < n; ++i) {
      const SiteKeyframe& k = keys[std::size_t(i)];
      put(out, std::int64_t(k.utime));
      for (const double v : poseToArray(k.T_map)) put(out, v);
      put(out, k.tile_x);
      put(out, k.tile_y);
      put(out, k.offset);
      put(out, k.count);
      put(out, k.step);
      const std::vector<float>& cells = closer.places().entry(i).descriptor.cells();
      if (cells.size() != std::size_t(descriptor.rings) * std::size_t(descriptor.sectors))
        throw std::logic_error("site map: a keyframe's descriptor does not have the configured size");
      out.write(reinterpret_cast<const char*>(cells.data()), static_cast<std::streamsize>(cells.size() * sizeof(float)));
    }
    if (!out) throw std::runtime_error("site map " + tmp + ": write failed (disk full?)");
  }
  fs::rename(tmp, index, ec);
  if (ec) throw std::runtime_error("site map " + index + ": " + ec.message());
}

SiteMap::SiteMap(const std::string& dir, double budget_mb, const PlaceDescriptorConfig& descriptor)
    : dir_(dir), budget_bytes_(static_cast<std::size_t>(std::max(0.0, budget_mb) * 1024.0 * 1024.0)) {
  Reader in(dir + "/site.bin");
  char magic[8];
  in.bytes(magic, sizeof magic, "the header");
  if (std::memcmp(magic, kSiteMagic, sizeof magic) != 0) in.fail("not a livo site map (bad magic)");
  if (const auto v = in.get<std::uint32_t>("the header"); v != kVersion)
    in.fail("version " + std::to_string(v) + ", this build reads version " + std::to_string(kVersion));
  if (in.get<std::uint32_t>("the header") != kByteOrder) in.fail("written on a machine of the other byte order");
  tile_m_ = in.get<double>("the header");
  const auto rings = in.get<std::int32_t>("the header"), sectors = in.get<std::int32_t>("the header");
  const double min_r = in.get<double>("the header"), max_r = in.get<double>("the header"),
               cap = in.get<double>("the header");
  if (!(tile_m_ > 0) || !std::isfinite(tile_m_)) in.fail("bad tile edge");
  if (rings != descriptor.rings || sectors != descriptor.sectors || min_r != descriptor.min_range_m ||
      max_r != descriptor.max_range_m || cap != descriptor.height_cap_m)
    in.fail("made with a place descriptor of " + std::to_string(rings) + " x " + std::to_string(sectors) + " over (" +
            std::to_string(min_r) + ", " + std::to_string(max_r) + "] m, height " + std::to_string(cap) +
            " m; this run's loop section gives " + std::to_string(descriptor.rings) + " x " +
            std::to_string(descriptor.sectors) + " over (" + std::to_string(descriptor.min_range_m) + ", " +
            std::to_string(descriptor.max_range_m) + "] m, height " + std::to_string(descriptor.height_cap_m) +
            " m (descriptors of different kinds cannot be compared)");
  const auto n = in.get<std::uint64_t>("the header");
  const std::size_t cells = std::size_t(rings) * std::size_t(sectors);
  const std::uint64_t per_key = 8 + 56 + 8 + 16 + 8 + cells * sizeof(float);
  if (n > in.remaining() / per_key)
    in.fail("declares " + std::to_string(n) + " keyframes but holds bytes for " + std::to_string(in.remaining() / per_key));
  keyframes_.resize(static_cast<std::size_t>(n));
  Utime last = -1;
  for (std::size_t i = 0; i < keyframes_.size(); ++i) {
    SiteKeyframe& k = keyframes_[i];
    k.utime = in.get<std::int64_t>("a keyframe");
    double pose[7];
    for (double& v : pose) v = in.get<double>("a keyframe");
    for (const double v : pose)
      if (!std::isfinite(v)) in.fail("keyframe " + std::to_string(i) + ": non-finite pose");
    if (!(std::abs(std::hypot(std::hypot(pose[3], pose[4]), std::hypot(pose[5], pose[6])) - 1.0) < 1e-3))
      in.fail("keyframe " + std::to_string(i) + ": orientation is not a unit quaternion");
    if (k.utime <= last) in.fail("keyframe " + std::to_string(i) + ": time not after the keyframe before it");
    last = k.utime;
    k.T_map = poseFromArray(pose);
    k.tile_x = in.get<std::int32_t>("a keyframe");
    k.tile_y = in.get<std::int32_t>("a keyframe");
    k.offset = in.get<std::uint64_t>("a keyframe");
    k.count = in.get<std::uint64_t>("a keyframe");
    k.step = in.get<double>("a keyframe");
    if (!(k.step > 0) || !std::isfinite(k.step)) in.fail("keyframe " + std::to_string(i) + ": bad point step");
    if (k.count > (std::uint64_t(1) << 32) || k.offset > (std::uint64_t(1) << 40))
      in.fail("keyframe " + std::to_string(i) + ": implausible point count or offset");
    std::vector<float> c(cells);
    in.bytes(c.data(), cells * sizeof(float), "a keyframe's descriptor");
    try {
      k.descriptor = PlaceDescriptor::fromCells(rings, sectors, std::move(c));
    } catch (const std::exception& e) {
      in.fail("keyframe " + std::to_string(i) + ": " + e.what());
    }
  }
  if (in.remaining() != 0) in.fail(std::to_string(in.remaining()) + " bytes after the last keyframe");
}

std::size_t SiteMap::indexBytes() const {
  std::size_t b = keyframes_.capacity() * sizeof(SiteKeyframe);
  for (const SiteKeyframe& k : keyframes_) b += k.descriptor.cells().capacity() * sizeof(float) * 3 / 2;  // + keys, norms
  return b;
}

const SiteMap::Tile& SiteMap::tile(const TileKey& key) {
  if (auto it = tiles_.find(key); it != tiles_.end()) {
    lru_.splice(lru_.begin(), lru_, it->second.lru);
    return it->second;
  }
  const std::string path = tilePath(dir_, key.first, key.second);
  Reader in(path);
  char magic[8];
  in.bytes(magic, sizeof magic, "the header");
  if (std::memcmp(magic, kTileMagic, sizeof magic) != 0) in.fail("not a livo site map tile (bad magic)");
  const std::uint64_t rem = in.remaining();
  if (rem % kPointBytes != 0) in.fail("size is not a whole number of points");
  Tile t;
  t.points.resize(static_cast<std::size_t>(rem / kPointBytes));
  in.bytes(t.points.data(), static_cast<std::size_t>(rem), "the points");
  ++tile_reads_;
  bytes_held_ += t.points.size() * kPointBytes;
  lru_.push_front(key);
  t.lru = lru_.begin();
  auto& stored = tiles_.emplace(key, std::move(t)).first->second;
  while (budget_bytes_ > 0 && bytes_held_ > budget_bytes_ && lru_.size() > 1) {  // the newest stays
    const TileKey old = lru_.back();
    lru_.pop_back();
    bytes_held_ -= tiles_.at(old).points.size() * kPointBytes;
    tiles_.erase(old);
  }
  return stored;
}

std::vector<Vec3> SiteMap::points(int i) {
  const SiteKeyframe& k = keyframe(i);
  const Tile& t = tile({k.tile_x, k.tile_y});
  if (k.offset + k.count > t.points.size())
    throw std::runtime_error("site map " + tilePath(dir_, k.tile_x, k.tile_y) + ": holds " +
                             std::to_string(t.points.size()) + " points, keyframe " + std::to_string(i) + " needs " +
                             std::to_string(k.offset + k.count));
  std::vector<std::array<std::int16_t, 3>> q(t.points.begin() + std::ptrdiff_t(k.offset),
                                             t.points.begin() + std::ptrdiff_t(k.offset + k.count));
  return PackedPoints(std::move(q), k.step).unpack();
}

}  // namespace livo
