// Binary map files (map_file.hpp): the file header, the hybrid map's content (the LiDAR map, whose
// encoding is in map_file_lidar.cpp, then both visual maps) and the visual points' encoding.
#include "livo/map/map_file.hpp"

#include "map_file_codec.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace livo {

using namespace map_codec;

namespace {

constexpr char kMagic[8] = {'L', 'I', 'V', 'O', 'M', 'A', 'P', '1'};
// Version 3: each point's long-term flag (VisualPoint::from_longterm) after its view count. Version 2:
// patch samples as bytes (PatchPyramid) and the view count. Versions 1 (float samples, no view count:
// taken as the observations it holds) and 2 are still read; without the flag, the points of the
// long-term section have it and those of the local section do not.
constexpr std::uint32_t kVersion = 3;
constexpr std::uint32_t kFloatPatchVersion = 1;
constexpr std::uint32_t kBytePatchVersion = 2;
constexpr std::uint64_t kMaxVisualPoints = 50'000'000;
constexpr std::uint32_t kMaxObservations = 10'000;

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

void putVisualPoint(std::ostream& os, const VisualPoint& p) {
  put(os, p.id);
  putVec(os, p.p_world);
  putVec(os, p.normal);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) put(os, p.cov(r, c));
  put(os, std::int32_t(p.reference)); put(os, std::uint8_t(p.converged)); put(os, std::int32_t(p.bad_updates));
  put(os, p.last_seen);
  put(os, std::uint32_t(p.obs.size()));
  put(os, p.viewCount());
  put(os, std::uint8_t(p.from_longterm));
  for (const VisualObservation& o : p.obs) {
    put(os, o.utime);
    put(os, o.patch.values);
    putPose(os, o.T_world_camera);
    putVec(os, o.px);
    put(os, o.inv_exposure); put(os, o.score);
  }
}

void getPatch(std::istream& is, std::uint32_t version, PatchPyramid& patch) {
  if (version != kFloatPatchVersion) {
    patch.values = get<decltype(patch.values)>(is, "patch");
    return;
  }
  const auto values = get<std::array<float, PatchPyramid::kValues>>(is, "patch");
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!PatchPyramid::isGrayValue(values[i]))
      throw std::runtime_error("patch sample " + std::to_string(values[i]) + " is not a gray value");
    patch.values[i] = PatchPyramid::quantize(values[i]);
  }
}

VisualPoint getVisualPoint(std::istream& is, std::uint32_t version) {
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
  p.views = version == kFloatPatchVersion ? std::int32_t(n)  // not stored: what the file holds
                                          : get<std::int32_t>(is, "view count");
  if (p.views < std::int32_t(n))
    throw std::runtime_error("view count " + std::to_string(p.views) + " below the observation count " + std::to_string(n));
  if (version > kBytePatchVersion) p.from_longterm = get<std::uint8_t>(is, "long-term flag") != 0;
  p.obs.resize(n);
  for (VisualObservation& o : p.obs) {
    o.utime = get<Utime>(is, "observation time");
    getPatch(is, version, o.patch);
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

std::size_t loadVisual(std::istream& is, std::uint32_t version, VisualMap& m) {
  const auto n = get<std::uint64_t>(is, "visual point count");
  if (n > kMaxVisualPoints) throw std::runtime_error("visual point count " + std::to_string(n) + " over the limit");
  for (std::uint64_t i = 0; i < n; ++i) {
    if (!m.insert(std::make_unique<VisualPoint>(getVisualPoint(is, version))))
      throw std::runtime_error("visual point " + std::to_string(i) + ": duplicate id or bad position");
  }
  return std::size_t(n);
}

}  // namespace

// ---- HybridMap content: the LiDAR map, then the local and the long-term visual map ----
namespace {
void saveContent(std::ostream& os, const HybridMap& map) {
  map.lidar().voxels().save(os);
  saveVisual(os, map.visual().local());
  saveVisual(os, map.visual().longterm());
}

// Counters, cube centres and pending slide work are not part of it: the first update() after loading
// centres the cubes at the robot again (and, with a cap, makes an exact byte count).
void loadContent(std::istream& is, std::uint32_t version, HybridMap& map) {
  map.clear();
  try {
    map.lidar().load(is);
    loadVisual(is, version, map.visual().local());
    loadVisual(is, version, map.visual().longterm());  // marks its points (VisualMap's long-term flag)
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
    if (version < kFloatPatchVersion || version > kVersion)
      throw std::runtime_error("version " + std::to_string(version) + ", this build reads " +
                               std::to_string(kFloatPatchVersion) + " to " + std::to_string(kVersion));
    const double vs = get<double>(is, "voxel size");
    const double vvs = get<double>(is, "visual voxel size");
    const double cfg_vs = map.lidar().voxels().config().voxel_size_m;
    const double cfg_vvs = map.visual().local().config().voxel_size_m;
    if (vs != cfg_vs || vvs != cfg_vvs)
      throw std::runtime_error("written with voxel sizes " + std::to_string(vs) + " / " + std::to_string(vvs) +
                               " m, configured " + std::to_string(cfg_vs) + " / " + std::to_string(cfg_vvs) + " m");
    loadContent(is, version, map);
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
