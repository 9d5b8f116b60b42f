// Binary map files (map_file.hpp): the save/load members of OctreeNode and VoxelMap, the hybrid
// map's content (LiDAR map and both visual maps) and the file header.
#include "livo/map/map_file.hpp"

#include "octree_node.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace livo {
namespace {

constexpr char kMagic[8] = {'L', 'I', 'V', 'O', 'M', 'A', 'P', '1'};
constexpr std::uint32_t kVersion = 1;
constexpr std::uint64_t kMaxRoots = 100'000'000;
constexpr std::uint64_t kMaxVisualPoints = 50'000'000;
constexpr std::uint32_t kMaxObservations = 10'000;

template <class T>
void put(std::ostream& os, const T& v) {
  static_assert(std::is_trivially_copyable<T>::value, "POD only");
  os.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <class T>
T get(std::istream& is, const char* what) {
  static_assert(std::is_trivially_copyable<T>::value, "POD only");
  T v;
  if (!is.read(reinterpret_cast<char*>(&v), sizeof(T)))
    throw std::runtime_error(std::string("truncated while reading ") + what);
  return v;
}

void putVec(std::ostream& os, const Eigen::Ref<const Eigen::VectorXd>& v) {
  for (Eigen::Index i = 0; i < v.size(); ++i) put(os, v[i]);
}

double getFinite(std::istream& is, const char* what) {
  const double v = get<double>(is, what);
  if (!std::isfinite(v)) throw std::runtime_error(std::string("non-finite ") + what);
  return v;
}

Vec3 getVec3(std::istream& is, const char* what) {
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = getFinite(is, what);
  return v;
}

void putPose(std::ostream& os, const Pose& T) {
  const Eigen::Quaterniond q(T.linear());
  put(os, T.translation().x()); put(os, T.translation().y()); put(os, T.translation().z());
  put(os, q.x()); put(os, q.y()); put(os, q.z()); put(os, q.w());
}

Pose getPose(std::istream& is) {
  const Vec3 t = getVec3(is, "pose translation");
  double q[4];
  for (double& c : q) c = getFinite(is, "pose quaternion");
  Eigen::Quaterniond quat(q[3], q[0], q[1], q[2]);
  if (!(quat.norm() > 1e-9)) throw std::runtime_error("zero pose quaternion");
  Pose T = Pose::Identity();
  T.linear() = quat.normalized().toRotationMatrix();
  T.translation() = t;
  return T;
}

void putPlane(std::ostream& os, const Plane& p) {
  putVec(os, p.center);
  putVec(os, p.normal);
  put(os, p.d);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) put(os, p.cov_nq(r, c));
  put(os, p.radius); put(os, p.eig_min); put(os, p.eig_mid); put(os, p.eig_max);
  put(os, std::int32_t(p.num_points)); put(os, std::int32_t(p.layer)); put(os, std::uint8_t(p.is_plane));
}

Plane getPlane(std::istream& is) {
  Plane p;
  p.center = getVec3(is, "plane centre");
  p.normal = getVec3(is, "plane normal");
  p.d = getFinite(is, "plane offset");
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) p.cov_nq(r, c) = getFinite(is, "plane covariance");
  p.radius = getFinite(is, "plane radius");
  p.eig_min = getFinite(is, "plane eigenvalue");
  p.eig_mid = getFinite(is, "plane eigenvalue");
  p.eig_max = getFinite(is, "plane eigenvalue");
  p.num_points = get<std::int32_t>(is, "plane point count");
  p.layer = get<std::int32_t>(is, "plane layer");
  p.is_plane = get<std::uint8_t>(is, "plane flag") != 0;
  return p;
}

void putVisualPoint(std::ostream& os, const VisualPoint& p) {
  put(os, p.id);
  putVec(os, p.p_world);
  putVec(os, p.normal);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) put(os, p.cov(r, c));
  put(os, std::int32_t(p.reference)); put(os, std::uint8_t(p.converged)); put(os, std::int32_t(p.bad_updates));
  put(os, p.last_seen);
  put(os, std::uint32_t(p.obs.size()));
  for (const VisualObservation& o : p.obs) {
    put(os, o.utime);
    put(os, o.patch.values);
    putPose(os, o.T_world_camera);
    putVec(os, o.px);
    put(os, o.inv_exposure); put(os, o.score);
  }
}

VisualPoint getVisualPoint(std::istream& is) {
  VisualPoint p;
  p.id = get<std::int64_t>(is, "visual point id");
  p.p_world = getVec3(is, "visual point position");
  p.normal = getVec3(is, "visual point normal");
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) p.cov(r, c) = getFinite(is, "visual point covariance");
  p.reference = get<std::int32_t>(is, "reference index");
  p.converged = get<std::uint8_t>(is, "converged flag") != 0;
  p.bad_updates = get<std::int32_t>(is, "bad update count");
  p.last_seen = get<Utime>(is, "last seen time");
  const auto n = get<std::uint32_t>(is, "observation count");
  if (n > kMaxObservations) throw std::runtime_error("observation count " + std::to_string(n) + " over the limit");
  if (p.reference < -1 || p.reference >= std::int32_t(n))
    throw std::runtime_error("reference index " + std::to_string(p.reference) + " outside the observations");
  p.obs.resize(n);
  for (VisualObservation& o : p.obs) {
    o.utime = get<Utime>(is, "observation time");
    o.patch.values = get<decltype(o.patch.values)>(is, "patch");
    o.T_world_camera = getPose(is);
    o.px.x() = getFinite(is, "observation pixel");
    o.px.y() = getFinite(is, "observation pixel");
    o.inv_exposure = get<float>(is, "inverse exposure");
    o.score = get<float>(is, "observation score");
  }
  return p;
}

void saveVisual(std::ostream& os, const VisualMap& m) {
  put(os, std::uint64_t(m.size()));
  m.forEach([&os](const VisualPoint& p) { putVisualPoint(os, p); });
}

std::size_t loadVisual(std::istream& is, VisualMap& m) {
  const auto n = get<std::uint64_t>(is, "visual point count");
  if (n > kMaxVisualPoints) throw std::runtime_error("visual point count " + std::to_string(n) + " over the limit");
  for (std::uint64_t i = 0; i < n; ++i) {
    if (!m.insert(std::make_unique<VisualPoint>(getVisualPoint(is))))
      throw std::runtime_error("visual point " + std::to_string(i) + ": duplicate id or bad position");
  }
  return std::size_t(n);
}

}  // namespace

// ---- OctreeNode ----
void OctreeNode::save(std::ostream& os) const {
  putVec(os, center_);
  put(os, layer_); put(os, std::uint8_t(state_)); put(os, std::uint8_t(update_enabled_)); put(os, new_points_);
  put(os, std::uint32_t(points_.size()));
  for (const MapPoint& p : points_) {
    putVec(os, p.p_world);
    put(os, p.cov_upper);
  }
  put(os, std::uint8_t(plane_ != nullptr));
  if (plane_) putPlane(os, *plane_);
  std::uint8_t mask = 0;
  if (children_)
    for (std::size_t i = 0; i < 8; ++i)
      if ((*children_)[i]) mask |= std::uint8_t(1u << i);
  put(os, std::uint8_t(children_ != nullptr)); put(os, mask);
  if (children_)
    for (const auto& c : *children_)
      if (c) c->save(os);
}

std::unique_ptr<OctreeNode> OctreeNode::load(std::istream& is, const LoadLimits& limits, int layer) {
  const Vec3 center = getVec3(is, "node centre");
  const auto stored_layer = get<std::uint8_t>(is, "node layer");
  if (int(stored_layer) != layer) throw std::runtime_error("node layer " + std::to_string(stored_layer) + " at depth " + std::to_string(layer));
  auto node = std::make_unique<OctreeNode>(center, layer);
  const auto state = get<std::uint8_t>(is, "node state");
  if (state > std::uint8_t(State::Split)) throw std::runtime_error("node state " + std::to_string(state));
  node->state_ = State(state);
  node->update_enabled_ = get<std::uint8_t>(is, "node update flag") != 0;
  node->new_points_ = get<std::uint16_t>(is, "node new points");
  const auto n = get<std::uint32_t>(is, "node point count");
  if (n > limits.max_points) throw std::runtime_error("node point count " + std::to_string(n) + " over the limit");
  node->points_.resize(n);
  for (MapPoint& p : node->points_) {
    p.p_world = getVec3(is, "map point");
    p.cov_upper = get<std::array<float, 6>>(is, "map point covariance");
  }
  if (get<std::uint8_t>(is, "plane flag")) node->plane_ = std::make_unique<Plane>(getPlane(is));
  const bool has_children = get<std::uint8_t>(is, "children flag") != 0;
  const auto mask = get<std::uint8_t>(is, "children mask");
  if (has_children) {
    if (layer >= limits.max_layer) throw std::runtime_error("octree deeper than max_layer");
    node->children_ = std::make_unique<Children>();
    for (std::size_t i = 0; i < 8; ++i)
      if (mask & (1u << i)) (*node->children_)[i] = load(is, limits, layer + 1);
  }
  return node;
}

// ---- VoxelMap ----
void VoxelMap::save(std::ostream& os) const {
  put(os, std::uint64_t(roots_.size()));
  for (const auto& kv : roots_) {
    put(os, kv.first.x); put(os, kv.first.y); put(os, kv.first.z);
    kv.second->save(os);
  }
}

void VoxelMap::load(std::istream& is) {
  clear();
  try {
    const auto n = get<std::uint64_t>(is, "root voxel count");
    if (n > kMaxRoots) throw std::runtime_error("root voxel count " + std::to_string(n) + " over the limit");
    OctreeNode::LoadLimits lim;
    lim.max_layer = config_.max_layer;
    lim.max_points = std::size_t(std::max(config_.max_points, 1)) * 2 + 1024;
    for (std::uint64_t i = 0; i < n; ++i) {
      VoxelKey k;
      k.x = get<std::int64_t>(is, "voxel key");
      k.y = get<std::int64_t>(is, "voxel key");
      k.z = get<std::int64_t>(is, "voxel key");
      if (!roots_.emplace(k, OctreeNode::load(is, lim, 0)).second) throw std::runtime_error("duplicate root voxel");
    }
  } catch (...) {
    clear();
    throw;
  }
}

// ---- HybridMap content: the LiDAR map, then the local and the long-term visual map ----
namespace {
void saveContent(std::ostream& os, const HybridMap& map) {
  map.lidar().voxels().save(os);
  saveVisual(os, map.visual().local());
  saveVisual(os, map.visual().longterm());
}

// Counters, cube centres and pending slide work are not part of it: the first update() after loading
// centres the cubes at the robot again (and, with a cap, makes an exact byte count).
void loadContent(std::istream& is, HybridMap& map) {
  map.clear();
  try {
    map.lidar().load(is);
    loadVisual(is, map.visual().local());
    loadVisual(is, map.visual().longterm());
  } catch (...) {
    map.clear();
    throw;
  }
  map.requestExactCount();
}
}  // namespace

// ---- files ----
std::string MapFileInfo::describe() const {
  std::ostringstream os;
  os << root_voxels << " voxels, " << planes << " planes, " << visual_points_local << " + " << visual_points_longterm
     << " visual points (local + long-term), " << std::fixed << std::setprecision(1) << double(file_bytes) / 1e6
     << " MB";
  return os.str();
}

namespace {
MapFileInfo infoOf(const HybridMap& map, std::size_t bytes) {
  MapFileInfo info;
  info.root_voxels = map.lidar().voxels().numRootVoxels();
  info.planes = map.lidar().voxels().numPlanes();
  info.visual_points_local = map.visual().local().size();
  info.visual_points_longterm = map.visual().longterm().size();
  info.file_bytes = bytes;
  return info;
}
}  // namespace

MapFileInfo saveMap(const std::string& path, const HybridMap& map) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream os(tmp, std::ios::binary | std::ios::trunc);
    if (!os) throw std::runtime_error("map file " + tmp + ": cannot open for writing: " + std::strerror(errno));
    saveMap(os, map);
    os.flush();
    if (!os) throw std::runtime_error("map file " + tmp + ": write failed: " + std::strerror(errno));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error("map file " + path + ": cannot rename " + tmp + ": " + ec.message());
  return infoOf(map, std::size_t(std::filesystem::file_size(path)));
}

MapFileInfo loadMap(std::istream& is, const std::string& name, HybridMap& map) {
  try {
    char magic[sizeof(kMagic)];
    if (!is.read(magic, sizeof(magic)) || std::memcmp(magic, kMagic, sizeof(kMagic)) != 0)
      throw std::runtime_error("not a livo map file (bad magic)");
    const auto version = get<std::uint32_t>(is, "version");
    if (version != kVersion)
      throw std::runtime_error("version " + std::to_string(version) + ", this build reads " + std::to_string(kVersion));
    const double vs = get<double>(is, "voxel size");
    const double vvs = get<double>(is, "visual voxel size");
    const double cfg_vs = map.lidar().voxels().config().voxel_size_m;
    const double cfg_vvs = map.visual().local().config().voxel_size_m;
    if (vs != cfg_vs || vvs != cfg_vvs)
      throw std::runtime_error("written with voxel sizes " + std::to_string(vs) + " / " + std::to_string(vvs) +
                               " m, configured " + std::to_string(cfg_vs) + " / " + std::to_string(cfg_vvs) + " m");
    loadContent(is, map);
    if (is.peek() != std::char_traits<char>::eof()) throw std::runtime_error("trailing bytes after the map");
  } catch (const std::exception& e) {
    map.clear();
    throw std::runtime_error("map file " + name + ": " + e.what());
  }
  return infoOf(map, 0);
}

MapFileInfo loadMap(const std::string& path, HybridMap& map) {
  std::ifstream is(path, std::ios::binary);
  if (!is) throw std::runtime_error("map file " + path + ": cannot open: " + std::strerror(errno));
  MapFileInfo info = loadMap(is, path, map);
  info.file_bytes = std::size_t(std::filesystem::file_size(path));
  return info;
}

MapFileInfo saveMap(std::ostream& os, const HybridMap& map) {
  os.write(kMagic, sizeof(kMagic));
  put(os, kVersion);
  put(os, map.lidar().voxels().config().voxel_size_m);
  put(os, map.visual().local().config().voxel_size_m);
  saveContent(os, map);
  return infoOf(map, 0);
}

}  // namespace livo
