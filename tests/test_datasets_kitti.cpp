// KITTI-style .bin scans to LCM logs, read back and compared with raw float32 bytes (xyz auto-detection,
// times files, dump layout, azimuth times against a simulated spin). Bad inputs must stop with an error
// naming the file and the byte size.
// livo-test-deps: livo_io livo_common opencv_core opencv_imgcodecs
#include "datasets_test_util.hpp"

#include "livo/datasets/kitti.hpp"
#include "livo/io/convert.hpp"
#include "livo/io/log.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <vector>

using namespace livo;
using namespace livo::test;

namespace {

void writeFloats(const fs::path& p, const std::vector<float>& v) {
  fs::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary);
  f.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(float)));
}

std::vector<float> readFloatsOracle(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  std::vector<float> v(bytes.size() / 4);
  std::memcpy(v.data(), bytes.data(), v.size() * 4);
  return v;
}

}  // namespace

// ---------------- KITTI-style scans ----------------

TEST(Kitti, Kitti00AutoDetectsXyzAndKeepsValues) {
  if (!fs::exists(kScans / "kitti_00")) LIVO_SKIP() << "shared data absent: " << kScans;
  // Note: despite the data README ("x,y,z,intensity"), these files hold x,y,z records: 000001.bin is
  // 1495260 bytes, a multiple of 12 but not of 16, and auto-detection must pick xyz for the folder.
  TempDir t;
  KittiOptions opt;
  const ConversionSummary sum = convertKitti((kScans / "kitti_00").string(), t / "k.lcm", opt);
  const DecodedLog log = readLog(t / "k.lcm");
  ASSERT_EQ(log.scans.size(), 2u);
  EXPECT_EQ(sum.channels.at("LIVO_LIDAR").events, 2u);
  const char* names[2] = {"000000.bin", "000001.bin"};
  for (int s = 0; s < 2; ++s) {
    const lidar_scan_t& m = log.scans[static_cast<std::size_t>(s)];
    const std::vector<float> raw = readFloatsOracle(kScans / "kitti_00" / names[s]);
    ASSERT_EQ(static_cast<std::size_t>(m.num_points) * 12, fs::file_size(kScans / "kitti_00" / names[s]));
    EXPECT_EQ(m.utime, s * 100'000);
    EXPECT_EQ(m.sensor, "generic");
    for (std::size_t i = 0; i < static_cast<std::size_t>(m.num_points); ++i) {
      ASSERT_EQ(m.x[i], raw[3 * i]);
      ASSERT_EQ(m.y[i], raw[3 * i + 1]);
      ASSERT_EQ(m.z[i], raw[3 * i + 2]);
      ASSERT_EQ(m.time_offset_s[i], 0.f);
      ASSERT_EQ(m.ring[i], -1);
    }
  }
  // A single file of that folder is ambiguous (1496016 bytes is a multiple of 12 and 16).
  const std::string err = errorOf([&] { convertKitti((kScans / "kitti_00/000000.bin").string(), t / "a.lcm"); });
  EXPECT_TRUE(contains(err, "000000.bin: ambiguous record size")) << err;
  EXPECT_TRUE(contains(err, "--fields")) << err;
  EXPECT_FALSE(fs::exists(t / "a.lcm"));
}

TEST(Kitti, Newer06PairsTimesFiles) {
  if (!fs::exists(kScans / "newer_06")) LIVO_SKIP() << "shared data absent: " << kScans;
  TempDir t;
  KittiOptions opt;
  // Two series (raw_*, deskewed_*) in one folder: the converter must ask which one.
  EXPECT_TRUE(contains(errorOf([&] { convertKitti((kScans / "newer_06").string(), t / "n.lcm", opt); }),
                       "several scan series (deskewed_*, raw_*)"));
  opt.prefix = "raw_";
  opt.start_time_s = 5.0;
  opt.rate_hz = 20.0;
  convertKitti((kScans / "newer_06").string(), t / "n.lcm", opt);
  const DecodedLog log = readLog(t / "n.lcm");
  ASSERT_EQ(log.scans.size(), 3u);
  for (int s = 0; s < 3; ++s) {
    const std::string id = "0" + std::to_string(s);
    const std::vector<float> raw = readFloatsOracle(kScans / "newer_06" / ("raw_" + id + ".bin"));
    const std::vector<float> times = readFloatsOracle(kScans / "newer_06" / ("times_" + id + ".bin"));
    const lidar_scan_t& m = log.scans[static_cast<std::size_t>(s)];
    EXPECT_EQ(m.utime, 5'000'000 + s * 50'000);
    ASSERT_EQ(static_cast<std::size_t>(m.num_points), raw.size() / 3);
    ASSERT_EQ(static_cast<std::size_t>(m.num_points), times.size());
    for (std::size_t i = 0; i < times.size(); ++i) {
      ASSERT_EQ(m.x[i], raw[3 * i]);
      ASSERT_EQ(m.z[i], raw[3 * i + 2]);
      ASSERT_EQ(m.time_offset_s[i], times[i]);
    }
    EXPECT_GT(*std::max_element(m.time_offset_s.begin(), m.time_offset_s.end()), 0.09f);
  }
}

TEST(Kitti, DumpLayoutWithSubfolders) {
  if (!fs::exists(kScans / "kitti_07_dump")) LIVO_SKIP() << "shared data absent: " << kScans;
  TempDir t;
  KittiOptions opt;
  opt.synth_times = SynthTimes::Azimuth;
  convertKitti((kScans / "kitti_07_dump").string(), t / "d.lcm", opt);
  const DecodedLog log = readLog(t / "d.lcm");
  ASSERT_EQ(log.scans.size(), 5u);
  for (std::size_t s = 0; s < 5; ++s) {
    const fs::path f = kScans / "kitti_07_dump" / ("00000" + std::to_string(s)) / "points.bin";
    EXPECT_EQ(static_cast<std::size_t>(log.scans[s].num_points) * 12, fs::file_size(f));
    for (float dt : log.scans[s].time_offset_s) {
      ASSERT_GE(dt, 0.f);
      ASSERT_LE(dt, 0.1f);
    }
  }
}

TEST(Kitti, AzimuthTimesMatchASimulatedSpin) {
  // Oracle: 4 rings stored ring after ring (KITTI order), each a full turn fired at a constant rate
  // starting at azimuth 30 degrees; spin clockwise (Velodyne) or counter-clockwise.
  for (const double spin : {-1.0, 1.0}) {
    LidarScan scan;
    std::vector<float> truth;
    const double period = 0.1;
    const int per_ring = 900;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> range(2.0, 50.0);
    for (int ring = 0; ring < 4; ++ring)
      for (int k = 0; k < per_ring; ++k) {
        const double t = period * k / per_ring;
        const double az = 30.0 * M_PI / 180.0 + spin * 2.0 * M_PI * t / period;
        const double r = range(rng);
        LidarPoint p;
        p.p_lidar = Eigen::Vector3f(static_cast<float>(r * std::cos(az)), static_cast<float>(r * std::sin(az)),
                                    static_cast<float>(0.1 * ring - 0.2));
        scan.points.push_back(p);
        truth.push_back(static_cast<float>(t));
      }
    scan.points[5].p_lidar.x() = std::nanf("");  // a NaN return gets offset 0
    synthAzimuthTimes(scan, period);
    EXPECT_EQ(scan.points[5].time_offset_s, 0.f);
    double worst = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      if (i == 5) continue;
      double d = std::abs(scan.points[i].time_offset_s - truth[i]);
      d = std::min(d, period - d);  // the very first firing may land at either end of the period
      worst = std::max(worst, d);
    }
    EXPECT_LT(worst, 1e-6) << "spin " << spin;
  }
}

TEST(Kitti, BadInputNamesTheFile) {
  TempDir t;
  writeFloats(t.path / "flat" / "000000.bin", std::vector<float>(12, 1.f));  // 48 bytes: 4 xyz or 3 xyzi
  writeFloats(t.path / "flat" / "000001.bin", std::vector<float>(7, 1.f));   // 28 bytes: neither
  std::string err = errorOf([&] { convertKitti(t / "flat", t / "o.lcm"); });
  EXPECT_TRUE(contains(err, "000001.bin: 28 bytes is neither a multiple of 12")) << err;
  KittiOptions xyzi;
  xyzi.fields = PointFields::Xyzi;
  err = errorOf([&] { convertKitti(t / "flat", t / "o.lcm", xyzi); });
  EXPECT_TRUE(contains(err, "000001.bin: 28 bytes is not a multiple of the record size 16")) << err;
  EXPECT_FALSE(fs::exists(t / "o.lcm"));

  // Ambiguous folder, resolved by an explicit layout.
  fs::remove(t.path / "flat" / "000001.bin");
  err = errorOf([&] { convertKitti(t / "flat", t / "o.lcm"); });
  EXPECT_TRUE(contains(err, "ambiguous record size")) << err;
  convertKitti(t / "flat", t / "o.lcm", xyzi);
  EXPECT_EQ(readLog(t / "o.lcm").scans.at(0).num_points, 3);

  // Times file: count mismatch, bad values, and a missing pair.
  writeFloats(t.path / "ser" / "raw_00.bin", std::vector<float>(9, 1.f));  // 3 xyz points (36 bytes)
  writeFloats(t.path / "ser" / "times_00.bin", {0.f, 0.05f});
  err = errorOf([&] { convertKitti(t / "ser", t / "o2.lcm"); });
  EXPECT_TRUE(contains(err, "raw_00.bin: 36 bytes fits neither 12 nor 16 bytes per point for the 2 times")) << err;
  KittiOptions xyz;
  xyz.fields = PointFields::Xyz;
  err = errorOf([&] { convertKitti(t / "ser", t / "o2.lcm", xyz); });
  EXPECT_TRUE(contains(err, "times_00.bin: 2 times for 3 points")) << err;
  writeFloats(t.path / "ser" / "times_00.bin", {0.f, std::nanf(""), 0.05f});
  err = errorOf([&] { convertKitti(t / "ser", t / "o2.lcm"); });
  EXPECT_TRUE(contains(err, "times_00.bin: time 1 (byte 4) is nan")) << err;
  writeFloats(t.path / "ser" / "times_00.bin", {0.f, 0.02f, 0.05f});
  writeFloats(t.path / "ser" / "raw_01.bin", std::vector<float>(9, 2.f));
  err = errorOf([&] { convertKitti(t / "ser", t / "o2.lcm"); });
  EXPECT_TRUE(contains(err, "raw_01.bin: no time file times_01.bin")) << err;
  writeFloats(t.path / "ser" / "times_01.bin", {0.f, 0.03f, 0.06f});
  convertKitti(t / "ser", t / "o2.lcm");
  const DecodedLog ok = readLog(t / "o2.lcm");
  ASSERT_EQ(ok.scans.size(), 2u);
  EXPECT_EQ(ok.scans[1].time_offset_s[2], 0.06f);

  // Missing folder, empty folder, empty file, dump subfolder without points.bin.
  EXPECT_TRUE(contains(errorOf([&] { convertKitti(t / "absent", t / "o3.lcm"); }), "absent: no such file or directory"));
  fs::create_directories(t.path / "empty");
  EXPECT_TRUE(contains(errorOf([&] { convertKitti(t / "empty", t / "o3.lcm"); }), "empty: no scans"));
  writeFloats(t.path / "zero" / "0.bin", {});
  EXPECT_TRUE(contains(errorOf([&] { convertKitti(t / "zero", t / "o3.lcm"); }), "0.bin: empty file"));
  writeFloats(t.path / "dump" / "000000" / "points.bin", std::vector<float>(3, 1.f));
  fs::create_directories(t.path / "dump" / "000001");
  EXPECT_TRUE(contains(errorOf([&] { convertKitti(t / "dump", t / "o3.lcm"); }), "000001/points.bin: missing file"));
}
