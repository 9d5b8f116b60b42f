#include "fuzz_targets.hpp"

#include "livo/common/config.hpp"
#include "livo/estimation/pipeline.hpp"
#include "livo/io/channels.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/io/loop_messages.hpp"
#include "livo/io/map_messages.hpp"
#include "livo/io/resume_messages.hpp"
#include "livo/map/map_file.hpp"
#include "livo/sensors/camera_model.hpp"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace livo::fuzz {
namespace {

/// A rejection must say why.
void requireReason(const std::string& why, const char* where) {
  ++outcomes().rejected;
  if (why.empty()) {
    std::fprintf(stderr, "fuzz: %s rejected an input without a message\n", where);
    std::abort();
  }
}

MessageLimits fuzzLimits() {
  MessageLimits lim;
  lim.max_message_bytes = 1 << 20;
  return lim;
}

/// decode + fromMsg; a valid message must survive toMsg -> encode -> decode -> fromMsg again.
template <class Msg, class T>
void roundTrip(const std::uint8_t* data, std::size_t size, const char* name,
               Validation (*from)(const Msg&, T&, const MessageLimits&)) {
  const MessageLimits lim = fuzzLimits();
  Msg m;
  Validation v = decode(data, size, m, lim);
  if (!v) return requireReason(v.error, name);
  T out;
  v = from(m, out, lim);
  if (!v) return requireReason(v.error, name);
  const Msg again = toMsg(out);
  const std::vector<std::uint8_t> bytes = encode(again);
  Msg m2;
  T out2;
  Validation v2 = decode(bytes.data(), bytes.size(), m2, lim);
  if (v2) v2 = from(m2, out2, lim);
  if (!v2) {
    std::fprintf(stderr, "fuzz: %s accepted a message whose re-encoding is rejected: %s\n", name, v2.error.c_str());
    std::abort();
  }
  ++outcomes().accepted;
}

// fromMsg overloads with a uniform signature.
Validation imuFrom(const livo::imu_t& m, ImuSample& o, const MessageLimits&) { return fromMsg(m, o); }
Validation scanFrom(const livo::lidar_scan_t& m, LidarScan& o, const MessageLimits& l) { return fromMsg(m, o, l); }
Validation imageFrom(const livo::image_t& m, Image& o, const MessageLimits& l) { return fromMsg(m, o, l); }
Validation frameFrom(const livo::frame_t& m, Frame& o, const MessageLimits& l) { return fromMsg(m, o, l); }
Validation stateFrom(const livo::filter_state_t& m, FilterSnapshot& o, const MessageLimits&) { return fromMsg(m, o); }
template <class Msg, class T>
Validation plainFrom(const Msg& m, T& o, const MessageLimits& l) {
  return fromMsg(m, o, l);
}

constexpr int kTypes = 17;

std::vector<std::uint8_t> tagged(int type, const std::vector<std::uint8_t>& bytes) {
  std::vector<std::uint8_t> out{std::uint8_t(type)};
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

VisualObservation seedObs() {
  VisualObservation o;
  o.utime = 1000;
  for (std::size_t i = 0; i < o.patch.values.size(); ++i) o.patch.values[i] = std::uint8_t(i % 200);
  o.px = Vec2(10, 20);
  o.score = 0.5f;
  return o;
}

VisualPoint seedPoint() {
  VisualPoint p;
  p.id = 7;
  p.p_world = Vec3(1, 2, 3);
  p.cov = Mat3::Identity() * 1e-4;
  p.obs = {seedObs()};
  p.reference = 0;
  return p;
}

SubmapPlane seedPlane() {
  SubmapPlane s;
  s.key = {1, -2, 3};
  s.layer = 1;
  s.octant = {{3, -1, -1}};
  s.plane.center = Vec3(0.6, -0.7, 1.7);
  s.plane.normal = Vec3::UnitZ();
  s.plane.d = -1.7;
  s.plane.cov_nq = Mat6::Identity() * 1e-6;
  s.plane.radius = 0.2;
  s.plane.num_points = 20;
  return s;
}

}  // namespace

int fuzzMessages(const std::uint8_t* data, std::size_t size) {
  if (size < 1) {  // no type byte: nothing to decode
    ++outcomes().rejected;
    return 0;
  }
  const int type = data[0] % kTypes;
  const std::uint8_t* d = data + 1;
  const std::size_t n = size - 1;
  switch (type) {
    case 0: roundTrip<livo::imu_t, ImuSample>(d, n, "imu_t", imuFrom); break;
    case 1: roundTrip<livo::lidar_scan_t, LidarScan>(d, n, "lidar_scan_t", scanFrom); break;
    case 2: roundTrip<livo::image_t, Image>(d, n, "image_t", imageFrom); break;
    case 3: roundTrip<livo::frame_t, Frame>(d, n, "frame_t", frameFrom); break;
    case 4: roundTrip<livo::map_query_t, MapQuery>(d, n, "map_query_t", plainFrom); break;
    case 5: roundTrip<livo::submap_t, Submap>(d, n, "submap_t", plainFrom); break;
    case 6: roundTrip<livo::map_update_t, MapUpdate>(d, n, "map_update_t", plainFrom); break;
    case 7: roundTrip<livo::map_stats_t, MapStats>(d, n, "map_stats_t", plainFrom); break;
    case 8: roundTrip<livo::odometry_t, OdometryOutput>(d, n, "odometry_t", plainFrom); break;
    case 9: roundTrip<livo::registered_scan_t, RegisteredScan>(d, n, "registered_scan_t", plainFrom); break;
    case 10: roundTrip<livo::estimator_stats_t, EstimatorStats>(d, n, "estimator_stats_t", plainFrom); break;
    case 11: roundTrip<livo::patch_t, VisualObservation>(d, n, "patch_t", plainFrom); break;
    case 12: roundTrip<livo::plane_t, SubmapPlane>(d, n, "plane_t", plainFrom); break;
    case 14: roundTrip<livo::filter_state_t, FilterSnapshot>(d, n, "filter_state_t", stateFrom); break;
    case 15: roundTrip<livo::resume_t, ResumeAnswer>(d, n, "resume_t", plainFrom); break;
    case 16: roundTrip<livo::map_correction_t, MapCorrection>(d, n, "map_correction_t", plainFrom); break;
    default: roundTrip<livo::visual_point_t, VisualPoint>(d, n, "visual_point_t", plainFrom); break;
  }
  return 0;
}

int fuzzConfig(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    ConfigFile file = ConfigFile::parse(text, "fuzz.yaml");
    const ConfigNode root = file.root();
    PipelineConfig cfg;
    cfg.load(root);
    ChannelConfig channels;
    channels.load(root.section("channels"));
    if (cfg.camera.enabled) CameraModel::create(cfg.camera);
    file.checkAllKeysUsed();
    ++outcomes().accepted;
  } catch (const std::exception& e) {
    requireReason(e.what(), "the config loader");
  }
  return 0;
}

int fuzzMapFile(const std::uint8_t* data, std::size_t size) {
  HybridMap map(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    loadMap(in, "fuzz.map", map);
    // A loaded map must be usable.
    map.update(Vec3::Zero());
    map.stats();
    ++outcomes().accepted;
  } catch (const std::exception& e) {
    requireReason(e.what(), "the map file loader");
  }
  return 0;
}

Outcomes& outcomes() {
  static Outcomes o;
  return o;
}

std::vector<std::pair<std::string, std::vector<std::uint8_t>>> seeds(const std::string& target) {
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> out;
  if (target == "messages") {
    ImuSample imu;
    imu.utime = 1000;
    imu.accel = Vec3(0, 0, 9.8);
    out.push_back({"imu", tagged(0, encode(toMsg(imu)))});
    LidarScan scan;
    scan.utime = 2000;
    scan.sensor = "avia";
    for (int i = 0; i < 4; ++i) {
      LidarPoint p;
      p.p_lidar = Eigen::Vector3f(1.f + float(i), 0.5f, 0.2f);
      p.time_offset_s = 0.01f * float(i);
      scan.points.push_back(p);
    }
    out.push_back({"scan", tagged(1, encode(toMsg(scan)))});
    Image img;
    img.utime = 3000;
    img.width = 4;
    img.height = 3;
    img.row_stride = 4;
    img.data.assign(12, 100);
    out.push_back({"image", tagged(2, encode(toMsg(img)))});
    Frame f;
    f.utime = 4000;
    f.sweep_start_utime = 3000;
    f.imu = {imu};
    f.imu[0].utime = 3500;
    f.sweep = scan;
    f.sweep.utime = 3000;
    f.has_image = true;
    f.image = img;
    f.image.utime = 4000;
    out.push_back({"frame", tagged(3, encode(toMsg(f)))});
    MapQuery q;
    q.utime = 5000;
    q.request_id = 3;
    q.keys = {{1, 2, 3}, {-4, 5, -6}};
    q.visual_keys = {{7, 8, 9}};
    q.want_visual = true;
    out.push_back({"query", tagged(4, encode(toMsg(q)))});
    Submap s;
    s.utime = 5000;
    s.request_id = 3;
    s.planes = {seedPlane()};
    s.visual_points = {seedPoint()};
    out.push_back({"submap", tagged(5, encode(toMsg(s)))});
    MapUpdate u;
    u.utime = 5000;
    u.request_id = 3;
    PointWithCov pw;
    pw.p_world = Vec3(1, 1, 1);
    pw.cov_world = Mat3::Identity() * 1e-4;
    u.points = {pw, pw};
    u.new_visual_points = {seedPoint()};
    u.observations = {{7, seedObs()}};
    out.push_back({"update", tagged(6, encode(toMsg(u)))});
    MapStats ms;
    ms.utime = 6000;
    ms.bytes = 1 << 20;
    out.push_back({"map_stats", tagged(7, encode(toMsg(ms)))});
    OdometryOutput o;
    o.utime = 7000;
    o.pose_cov = Mat6::Identity() * 1e-4;
    out.push_back({"odometry", tagged(8, encode(toMsg(o)))});
    RegisteredScan r;
    r.utime = 7000;
    r.points = {Eigen::Vector3f(1, 2, 3)};
    r.intensity = {1.f};
    r.rgb = {0x102030};
    out.push_back({"registered", tagged(9, encode(toMsg(r)))});
    EstimatorStats es;
    es.utime = 7000;
    es.total_ms = 5.f;
    out.push_back({"estimator_stats", tagged(10, encode(toMsg(es)))});
    out.push_back({"patch", tagged(11, encode(toMsg(seedObs())))});
    out.push_back({"plane", tagged(12, encode(toMsg(seedPlane())))});
    out.push_back({"visual_point", tagged(13, encode(toMsg(seedPoint())))});
    FilterSnapshot fs;
    fs.filter.state.utime = 8000;
    fs.filter.P = initialCovariance();
    out.push_back({"filter_state", tagged(14, encode(toMsg(fs)))});
    ResumeAnswer ra;
    ra.request_id = 9;
    ra.have_state = true;
    ra.snapshot = fs;
    ra.imu = {imu};
    ra.imu[0].utime = 8005;
    out.push_back({"resume", tagged(15, encode(toMsg(ra)))});
    MapCorrection mc;
    mc.utime = 9000;
    mc.keyframes_total = 3;
    mc.first = 1;
    mc.keyframes = {{8000, Pose::Identity(), Pose::Identity()}, {9000, Pose::Identity(), Pose::Identity()}};
    mc.keyframes[1].T_odom.translation() = Vec3(2, 0, 0);
    mc.keyframes[1].T_map.translation() = Vec3(1.9, 0.1, 0);
    mc.loops = {{0, 2}};
    mc.solves = 1;
    out.push_back({"map_correction", tagged(16, encode(toMsg(mc)))});
  } else if (target == "config") {
    for (const char* name : {"avia.yaml", "sim_demo.yaml", "mid360.yaml"}) {
      std::ifstream f(std::string(LIVO_SOURCE_DIR) + "/config/" + name, std::ios::binary);
      std::stringstream ss;
      ss << f.rdbuf();
      const std::string t = ss.str();
      if (!t.empty()) out.push_back({name, std::vector<std::uint8_t>(t.begin(), t.end())});
    }
  } else if (target == "mapfile") {
    HybridMap map(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
    std::vector<PointWithCov> pts;
    for (int i = 0; i < 400; ++i) {
      PointWithCov p;
      p.p_world = Vec3(0.01 * (i % 20), 0.01 * (i / 20), 0.001 * (i % 3));
      p.cov_world = Mat3::Identity() * 1e-4;
      pts.push_back(p);
    }
    map.lidar().insert(pts);
    map.visual().upsert(seedPoint());
    std::ostringstream os;
    saveMap(os, map);
    const std::string t = os.str();
    out.push_back({"map", std::vector<std::uint8_t>(t.begin(), t.end())});
  } else {
    throw std::invalid_argument("fuzz::seeds: unknown target '" + target + "'");
  }
  return out;
}

}  // namespace livo::fuzz
