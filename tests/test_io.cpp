// libs/io: message round trips for every type, pre-decode checks of declared counts, validation errors
// that name the field, struct <-> message conversions, and LCM log writing/reading (truncation, garbage).
#include "livo/io/convert.hpp"
#include "livo/io/image_convert.hpp"
#include "livo/io/log.hpp"

#include <livo/estimator_stats_t.hpp>
#include <livo/map_query_t.hpp>
#include <livo/map_stats_t.hpp>
#include <livo/map_update_t.hpp>
#include <livo/odometry_t.hpp>
#include <livo/registered_scan_t.hpp>
#include <livo/submap_t.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

using namespace livo;

namespace {

std::mt19937 rng(42);
double rnd() { return std::uniform_real_distribution<double>(-100, 100)(rng); }
template <class T, std::size_t N>
void fill(T (&a)[N]) {
  for (auto& v : a) v = static_cast<T>(rnd());
}
template <class T, std::size_t N, std::size_t M>
void fill(T (&a)[N][M]) {
  for (auto& row : a) fill(row);
}
template <class T>
std::vector<T> randVec(int n) {
  std::vector<T> v(static_cast<std::size_t>(n));
  for (auto& x : v) x = static_cast<T>(rnd());
  return v;
}

livo::imu_t makeImu() {
  livo::imu_t m{};
  m.utime = 1700000000123456;
  fill(m.angular_velocity);
  fill(m.linear_acceleration);
  return m;
}
livo::lidar_scan_t makeScan(int n) {
  livo::lidar_scan_t m{};
  m.utime = 1700000000000000;
  m.num_points = n;
  m.x = randVec<float>(n); m.y = randVec<float>(n); m.z = randVec<float>(n);
  m.time_offset_s.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) m.time_offset_s[static_cast<std::size_t>(i)] = 0.1f * i / std::max(1, n);
  m.intensity = randVec<float>(n);
  m.ring = randVec<std::int16_t>(n);
  m.sensor = "avia";
  return m;
}
livo::image_t makeImage(int w, int h) {
  livo::image_t m{};
  m.utime = 1700000000050000;
  m.width = w; m.height = h; m.row_stride = w; m.pixel_format = livo::image_t::GRAY8;
  m.exposure_time_s = 0.005f;
  m.size = w * h;
  m.data = randVec<std::uint8_t>(m.size);
  return m;
}
livo::patch_t makePatch() {
  livo::patch_t p{};
  p.utime = 17;
  p.levels = 3; p.size = 8; p.num_values = 192;
  p.values = randVec<float>(192);
  fill(p.T_world_camera); fill(p.pixel);
  p.inv_exposure = 1.f; p.score = 0.5f;
  return p;
}
livo::visual_point_t makeVisualPoint(int patches) {
  livo::visual_point_t v{};
  v.id = 99; fill(v.position); fill(v.normal); fill(v.position_cov);
  v.converged = true; v.reference = 0;
  v.num_patches = patches;
  for (int i = 0; i < patches; ++i) v.patches.push_back(makePatch());
  return v;
}

template <class Msg>
void expectRoundTrip(const Msg& m) {
  const auto bytes = encode(m);
  Msg back;
  const Validation v = decode(bytes.data(), bytes.size(), back);
  ASSERT_TRUE(v) << Msg::getTypeName() << ": " << v.error;
  EXPECT_EQ(encode(back), bytes) << Msg::getTypeName();
}

// Overwrites the big-endian int32 at byte offset `at` of an encoded buffer.
void pokeInt32(std::vector<std::uint8_t>& b, std::size_t at, std::int32_t value) {
  const auto u = static_cast<std::uint32_t>(value);
  b[at] = std::uint8_t(u >> 24); b[at + 1] = std::uint8_t(u >> 16); b[at + 2] = std::uint8_t(u >> 8); b[at + 3] = std::uint8_t(u);
}

std::string tmpPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("livo_test_io_" + std::to_string(::getpid()) + "_" + name)).string();
}

}  // namespace

// toGray8 taking its input: a packed GRAY8 image moves (same pixels, no copy left behind); a strided
// GRAY8 and an RGB8 image convert exactly as the copying overload does (the oracle).
TEST(ImageConvert, MovingOverloadMovesPackedGrayAndConvertsTheRest) {
  Image packed;
  packed.utime = 7;
  packed.width = 4;
  packed.height = 2;
  packed.row_stride = 4;
  packed.exposure_time_s = 0.01f;
  for (int i = 0; i < 8; ++i) packed.data.push_back(std::uint8_t(10 * i));
  Image copied, moved;
  std::string err;
  ASSERT_TRUE(toGray8(packed, copied, &err)) << err;
  const std::uint8_t* pixels = packed.data.data();
  ASSERT_TRUE(toGray8(std::move(packed), moved, &err)) << err;
  EXPECT_EQ(moved.data.data(), pixels);  // the buffer itself moved
  EXPECT_EQ(moved.data, copied.data);
  EXPECT_EQ(moved.utime, copied.utime);
  EXPECT_EQ(moved.row_stride, copied.row_stride);
  EXPECT_EQ(moved.exposure_time_s, copied.exposure_time_s);

  Image strided = copied;
  strided.row_stride = 6;
  strided.data = {1, 2, 3, 4, 0, 0, 5, 6, 7, 8, 0, 0};
  Image rgb;
  rgb.width = 2;
  rgb.height = 1;
  rgb.row_stride = 6;
  rgb.format = PixelFormat::Rgb8;
  rgb.data = {255, 0, 0, 0, 0, 255};
  for (const Image& in : {strided, rgb}) {
    Image a, b;
    ASSERT_TRUE(toGray8(in, a, &err)) << err;
    ASSERT_TRUE(toGray8(Image(in), b, &err)) << err;
    EXPECT_EQ(a.data, b.data);
    EXPECT_EQ(b.row_stride, b.width);
  }
}

TEST(Messages, RoundTripEveryType) {
  expectRoundTrip(makeImu());
  expectRoundTrip(makeScan(1000));
  expectRoundTrip(makeScan(0));
  expectRoundTrip(makeImage(64, 48));

  livo::frame_t f{};
  f.utime = 10; f.sweep_start_utime = 5; f.num_imu = 3;
  for (int i = 0; i < 3; ++i) f.imu.push_back(makeImu());
  f.sweep = makeScan(50); f.has_image = true; f.image = makeImage(8, 8);
  expectRoundTrip(f);

  livo::map_query_t q{};
  q.utime = 1; q.request_id = 7; fill(q.position); fill(q.orientation); q.radius_m = 50;
  q.num_keys = 4; q.key_x = randVec<std::int32_t>(4); q.key_y = randVec<std::int32_t>(4); q.key_z = randVec<std::int32_t>(4);
  q.want_visual = true; fill(q.T_world_camera); q.max_visual_depth_m = 30;
  expectRoundTrip(q);

  livo::plane_t pl{};
  fill(pl.voxel_key); pl.layer = 1; fill(pl.octant); fill(pl.center); fill(pl.normal); fill(pl.covariance);
  pl.radius_m = 0.2f; pl.min_eigenvalue = 1e-4f; pl.num_points = 20; pl.frozen = false;
  expectRoundTrip(pl);
  expectRoundTrip(makePatch());
  expectRoundTrip(makeVisualPoint(3));

  livo::submap_t s{};
  s.utime = 1; s.request_id = 7; s.voxel_size_m = 0.5;
  s.num_planes = 2; s.planes = {pl, pl};
  s.num_visual_points = 2; s.visual_points = {makeVisualPoint(1), makeVisualPoint(0)};
  expectRoundTrip(s);

  livo::map_update_t u{};
  u.utime = 1; u.request_id = 7; fill(u.T_world_imu);
  u.num_points = 5;
  for (auto* a : {&u.x, &u.y, &u.z, &u.cov_xx, &u.cov_xy, &u.cov_xz, &u.cov_yy, &u.cov_yz, &u.cov_zz}) *a = randVec<float>(5);
  u.num_new_visual_points = 1; u.new_visual_points = {makeVisualPoint(2)};
  u.num_observations = 2; u.observation_point_ids = {3, 4}; u.observations = {makePatch(), makePatch()};
  expectRoundTrip(u);

  livo::odometry_t o{};
  o.utime = 1; fill(o.position); fill(o.orientation); fill(o.velocity); fill(o.gyro_bias); fill(o.accel_bias);
  fill(o.gravity); o.inv_exposure = 1; fill(o.covariance); o.status = livo::odometry_t::STATUS_DEGENERATE;
  expectRoundTrip(o);

  livo::registered_scan_t r{};
  r.utime = 1; r.num_points = 3;
  r.x = randVec<float>(3); r.y = randVec<float>(3); r.z = randVec<float>(3); r.intensity = randVec<float>(3);
  r.num_colors = 3; r.rgb = {0x102030, -1, 0xffffff};
  expectRoundTrip(r);

  livo::estimator_stats_t es{};
  es.utime = 1; es.frame_index = 2; es.lio_ms = 3; es.sigma_min = 0.3f; es.degenerate = true; es.n_points = 100;
  expectRoundTrip(es);
  livo::map_stats_t ms{};
  ms.utime = 1; ms.bytes = 1 << 30; ms.slides = 4;
  expectRoundTrip(ms);
}

TEST(Messages, PrecheckRejectsHugeDeclaredCountBeforeAllocating) {
  auto bytes = encode(makeScan(10));
  pokeInt32(bytes, 8 + 8, 1'500'000);  // num_points: fingerprint (8) + utime (8)
  livo::lidar_scan_t m{};
  const Validation v = decode(bytes.data(), bytes.size(), m);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("lidar_scan_t.num_points"), std::string::npos) << v.error;
  EXPECT_NE(v.error.find("bytes remain"), std::string::npos) << v.error;
  EXPECT_EQ(m.x.capacity(), 0u) << "nothing may be allocated from a rejected count";
}

TEST(Messages, PrecheckRejectsNegativeAndOverLimitCounts) {
  auto bytes = encode(makeImage(4, 4));
  pokeInt32(bytes, 8 + 8 + 4 + 4 + 4 + 1 + 4, -5);  // size
  livo::image_t img{};
  Validation v = decode(bytes.data(), bytes.size(), img);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("image_t.size: negative count"), std::string::npos) << v.error;

  MessageLimits lim;
  lim.max_points = 100;
  const auto big = encode(makeScan(101));
  livo::lidar_scan_t scan{};
  v = decode(big.data(), big.size(), scan, lim);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("exceeds the limit 100"), std::string::npos) << v.error;
}

TEST(Messages, PrecheckRejectsOversizedTruncatedAndForeignMessages) {
  MessageLimits lim;
  lim.max_message_bytes = 1000;
  const auto big = encode(makeImage(40, 40));
  livo::image_t img{};
  Validation v = decode(big.data(), big.size(), img, lim);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("exceeds max_message_bytes"), std::string::npos) << v.error;

  auto bytes = encode(makeScan(20));
  v = decode(bytes.data(), bytes.size() - 3, img);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("fingerprint"), std::string::npos) << v.error;
  livo::lidar_scan_t scan{};
  v = decode(bytes.data(), bytes.size() - 3, scan);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("lidar_scan_t"), std::string::npos) << v.error;
  bytes.push_back(0);
  v = decode(bytes.data(), bytes.size(), scan);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("trailing"), std::string::npos) << v.error;
  v = decode(bytes.data(), 4, scan);
  EXPECT_FALSE(v);
}

TEST(Messages, NestedCountsAreCheckedWithTheirPath) {
  livo::submap_t s{};
  s.num_visual_points = 1;
  s.visual_points = {makeVisualPoint(1)};
  auto bytes = encode(s);
  // Locate patch num_values (192) by scanning for its big-endian encoding and make it huge.
  bool poked = false;
  for (std::size_t i = 8; i + 4 <= bytes.size(); ++i) {
    if (bytes[i] == 0 && bytes[i + 1] == 0 && bytes[i + 2] == 0 && bytes[i + 3] == 192) {
      pokeInt32(bytes, i, 4000);
      poked = true;
      break;
    }
  }
  ASSERT_TRUE(poked);
  livo::submap_t back{};
  const Validation v = decode(bytes.data(), bytes.size(), back);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("submap_t.visual_points[0].patches[0].num_values"), std::string::npos) << v.error;
}

TEST(Messages, ValidationNamesTheField) {
  auto imu = makeImu();
  imu.linear_acceleration[1] = std::nan("");
  Validation v = validate(imu);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("imu_t.linear_acceleration"), std::string::npos) << v.error;

  auto scan = makeScan(10);
  scan.num_points = 11;  // declared count does not match the arrays
  v = validate(scan);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("lidar_scan_t.x: num_points declares 11"), std::string::npos) << v.error;
  scan = makeScan(10);
  scan.time_offset_s[3] = std::nanf("");
  v = validate(scan);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("time_offset_s[3]"), std::string::npos) << v.error;

  auto img = makeImage(10, 10);
  img.width = -1;
  v = validate(img);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("image_t.width"), std::string::npos) << v.error;
  img = makeImage(10, 10);
  img.row_stride = 5;
  EXPECT_NE(validate(img).error.find("image_t.row_stride"), std::string::npos);
  img = makeImage(10, 10);
  img.size = 50;
  img.data.resize(50);
  EXPECT_NE(validate(img).error.find("image_t.size"), std::string::npos);

  livo::frame_t f{};
  f.utime = 10; f.sweep_start_utime = 5; f.num_imu = 2;
  f.imu = {makeImu(), makeImu()};
  f.imu[1].angular_velocity[0] = INFINITY;
  f.sweep = makeScan(3);
  v = validate(f);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error.find("frame_t.imu[1].angular_velocity"), std::string::npos) << v.error;
}

TEST(Convert, StructRoundTripAndNonFinitePointsAreDroppedAndCounted) {
  LidarScan s;
  s.utime = 1700000000000000;
  s.sensor = "mid360";
  for (int i = 0; i < 100; ++i) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(float(i), -float(i), 0.5f);
    p.time_offset_s = 0.001f * i;
    p.intensity = float(i % 256);
    p.ring = std::int16_t(i % 4);
    s.points.push_back(p);
  }
  auto m = toMsg(s);
  m.x[10] = std::nanf("");
  m.z[20] = INFINITY;
  LidarScan back;
  std::size_t dropped = 0;
  ASSERT_TRUE(fromMsg(m, back, {}, &dropped));
  EXPECT_EQ(dropped, 2u);
  ASSERT_EQ(back.points.size(), 98u);
  EXPECT_EQ(back.sensor, "mid360");
  EXPECT_EQ(back.points[10].p_lidar.x(), 11.f);
  EXPECT_EQ(back.points[97].ring, 3);
  EXPECT_FLOAT_EQ(back.points[97].time_offset_s, 0.099f);

  ImuSample imu;
  imu.utime = 5;
  imu.gyro = Eigen::Vector3d(0.1, 0.2, 0.3);
  imu.accel = Eigen::Vector3d(0, 0, 9.81);
  ImuSample imu2;
  ASSERT_TRUE(fromMsg(toMsg(imu), imu2));
  EXPECT_EQ(imu2.gyro, imu.gyro);
  EXPECT_EQ(imu2.accel, imu.accel);

  Frame fr;
  fr.utime = 200; fr.sweep_start_utime = 100; fr.imu = {imu, imu}; fr.sweep = s; fr.has_image = true;
  fr.image.utime = 200; fr.image.width = 4; fr.image.height = 2; fr.image.row_stride = 4;
  fr.image.data = {1, 2, 3, 4, 5, 6, 7, 8};
  Frame fr2;
  const auto fm = toMsg(fr);
  const auto bytes = encode(fm);
  livo::frame_t fm2{};
  ASSERT_TRUE(decode(bytes.data(), bytes.size(), fm2));
  ASSERT_TRUE(fromMsg(fm2, fr2));
  EXPECT_EQ(fr2.imu.size(), 2u);
  EXPECT_EQ(fr2.sweep.points.size(), 100u);
  EXPECT_EQ(fr2.image.data, fr.image.data);
  fr.has_image = false;
  const auto fm3 = toMsg(fr);
  EXPECT_TRUE(validate(fm3));
}

TEST(Log, WriteAndReadBackInOrder) {
  const std::string path = tmpPath("order.lcm");
  const std::vector<Utime> stamps = {1700000000000000, 1700000000005000, 1700000000005000, 1700000000100000};
  {
    LogWriter w(path);
    for (std::size_t i = 0; i < stamps.size(); ++i) {
      auto imu = makeImu();
      imu.utime = stamps[i];
      w.write(i % 2 ? "LIVO_IMU" : "OTHER", stamps[i], imu);
    }
    EXPECT_EQ(w.eventsWritten(), stamps.size());
  }
  LogReader r(path);
  LogEvent ev;
  std::size_t i = 0;
  while (r.next(ev)) {
    ASSERT_LT(i, stamps.size());
    EXPECT_EQ(ev.timestamp, stamps[i]);
    EXPECT_EQ(ev.eventnum, static_cast<std::int64_t>(i));
    EXPECT_EQ(ev.channel, i % 2 ? "LIVO_IMU" : "OTHER");
    livo::imu_t m{};
    ASSERT_TRUE(decode(ev.data.data(), ev.data.size(), m));
    EXPECT_EQ(m.utime, stamps[i]);
    ++i;
  }
  EXPECT_EQ(i, stamps.size());
  EXPECT_EQ(r.position(), r.fileSize());
  std::filesystem::remove(path);
}

TEST(Log, TruncatedAndGarbageFilesGiveErrors) {
  const std::string path = tmpPath("trunc.lcm");
  {
    LogWriter w(path);
    for (int i = 0; i < 5; ++i) w.write("LIVO_LIDAR", 1000 * i, makeScan(100));
  }
  const auto full = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, full - 17);
  {
    LogReader r(path);
    LogEvent ev;
    int good = 0;
    try {
      while (r.next(ev)) ++good;
      FAIL() << "expected LogError";
    } catch (const LogError& e) {
      EXPECT_EQ(good, 4);
      EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("after 4 good events"), std::string::npos) << e.what();
    }
  }
  // Garbage in the middle of the file: bad sync word.
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(full / 2));
    const char junk[16] = "garbage-garbage";
    f.write(junk, sizeof(junk));
  }
  {
    LogReader r(path);
    LogEvent ev;
    EXPECT_THROW({ while (r.next(ev)) {} }, LogError);
  }
  std::filesystem::remove(path);
  EXPECT_THROW(LogReader("/nonexistent/dir/x.lcm"), LogError);
  EXPECT_THROW(LogWriter("/nonexistent/dir/x.lcm"), LogError);
}
