// Binary scan files: record layout detection, reading with size checks, per-point times.
#include "livo/datasets/kitti.hpp"
#include "livo/io/convert.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace livo {

namespace {

// The files are little-endian float32; the suite targets little-endian hosts (x86-64, aarch64).
std::uint64_t fileSize(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw DatasetError(path + ": missing file");
  const std::uint64_t n = fs::file_size(path, ec);
  if (ec) throw DatasetError(path + ": cannot read the size (" + ec.message() + ")");
  return n;
}

std::vector<float> readFloats(const std::string& path, std::uint64_t bytes) {
  std::vector<float> v(static_cast<std::size_t>(bytes / 4));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DatasetError(path + ": cannot open");
  in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(bytes));
  if (static_cast<std::uint64_t>(in.gcount()) != bytes)
    throw DatasetError(path + ": short read (" + std::to_string(in.gcount()) + " of " + std::to_string(bytes) +
                       " bytes)");
  return v;
}

std::string describeRecord(int bytes) {
  return bytes == 16 ? "16 (x,y,z,intensity float32)" : "12 (x,y,z float32)";
}

constexpr unsigned kXyz = 1, kXyzi = 2;

}  // namespace

int recordBytes(PointFields f) { return f == PointFields::Xyz ? 12 : f == PointFields::Xyzi ? 16 : 0; }

const char* toString(PointFields f) {
  return f == PointFields::Xyz ? "xyz" : f == PointFields::Xyzi ? "xyzi" : "auto";
}

PointFields resolvePointFields(const std::vector<KittiScanFile>& scans, PointFields requested) {
  if (scans.empty()) throw DatasetError("no scans to convert");
  if (requested != PointFields::Auto) {
    const int rb = recordBytes(requested);
    for (const auto& s : scans) {
      const std::uint64_t n = fileSize(s.points_path);
      if (n == 0) throw DatasetError(s.points_path + ": empty file (0 points)");
      if (n % static_cast<std::uint64_t>(rb) != 0)
        throw DatasetError(s.points_path + ": " + std::to_string(n) + " bytes is not a multiple of the record size " +
                           describeRecord(rb));
    }
    return requested;
  }
  unsigned all = kXyz | kXyzi;
  std::string first_xyz_only, first_xyzi_only;
  for (const auto& s : scans) {
    const std::uint64_t n = fileSize(s.points_path);
    if (n == 0) throw DatasetError(s.points_path + ": empty file (0 points)");
    unsigned fits = (n % 12 == 0 ? kXyz : 0u) | (n % 16 == 0 ? kXyzi : 0u);
    std::string why = std::to_string(n) + " bytes is neither a multiple of 12 (x,y,z float32) nor of 16 "
                      "(x,y,z,intensity float32)";
    if (!s.times_path.empty()) {
      const std::uint64_t tn = fileSize(s.times_path);
      if (tn % 4 != 0)
        throw DatasetError(s.times_path + ": " + std::to_string(tn) + " bytes is not a multiple of 4 (float32 times)");
      const std::uint64_t points = tn / 4;
      fits &= (n == 12 * points ? kXyz : 0u) | (n == 16 * points ? kXyzi : 0u);
      why = std::to_string(n) + " bytes fits neither 12 nor 16 bytes per point for the " + std::to_string(points) +
            " times in " + s.times_path;
    }
    if (fits == 0) throw DatasetError(s.points_path + ": " + why);
    if (fits == kXyz && first_xyz_only.empty()) first_xyz_only = s.points_path;
    if (fits == kXyzi && first_xyzi_only.empty()) first_xyzi_only = s.points_path;
    all &= fits;
  }
  if (all == kXyz) return PointFields::Xyz;
  if (all == kXyzi) return PointFields::Xyzi;
  if (all == 0)
    throw DatasetError("record size differs between files: " + first_xyz_only + " fits only x,y,z (12 bytes), " +
                       first_xyzi_only + " only x,y,z,intensity (16 bytes)");
  throw DatasetError(scans.front().points_path + (scans.size() > 1 ? " and the other scans" : "") +
                     ": ambiguous record size (every size is a multiple of both 12 and 16 bytes); pass "
                     "--fields xyz or --fields xyzi");
}

std::vector<float> readTimesFile(const std::string& path, std::size_t expected_points) {
  const std::uint64_t n = fileSize(path);
  if (n % 4 != 0)
    throw DatasetError(path + ": " + std::to_string(n) + " bytes is not a multiple of 4 (float32 times)");
  if (n / 4 != expected_points)
    throw DatasetError(path + ": " + std::to_string(n / 4) + " times for " + std::to_string(expected_points) +
                       " points");
  std::vector<float> t = readFloats(path, n);
  for (std::size_t i = 0; i < t.size(); ++i)
    if (!std::isfinite(t[i]) || t[i] < 0.f || t[i] > 10.f)
      throw DatasetError(path + ": time " + std::to_string(i) + " (byte " + std::to_string(4 * i) + ") is " +
                         std::to_string(t[i]) + " s, expected 0..10 s within the sweep");
  return t;
}

LidarScan readKittiScan(const KittiScanFile& file, PointFields fields, Utime utime, const std::string& sensor) {
  const int rb = recordBytes(fields);
  if (rb == 0) throw DatasetError(file.points_path + ": record layout not resolved (auto)");
  const std::uint64_t n = fileSize(file.points_path);
  if (n == 0) throw DatasetError(file.points_path + ": empty file (0 points)");
  if (n % static_cast<std::uint64_t>(rb) != 0)
    throw DatasetError(file.points_path + ": " + std::to_string(n) + " bytes is not a multiple of the record size " +
                       describeRecord(rb));
  const std::uint64_t count = n / static_cast<std::uint64_t>(rb);
  const MessageLimits lim;
  if (count > static_cast<std::uint64_t>(lim.max_points))
    throw DatasetError(file.points_path + ": " + std::to_string(count) + " points exceed the message limit " +
                       std::to_string(lim.max_points));
  std::vector<float> times;
  if (!file.times_path.empty()) times = readTimesFile(file.times_path, static_cast<std::size_t>(count));
  const std::vector<float> v = readFloats(file.points_path, n);
  const std::size_t stride = static_cast<std::size_t>(rb / 4);

  LidarScan scan;
  scan.utime = utime;
  scan.sensor = sensor;
  scan.points.resize(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    LidarPoint& p = scan.points[i];
    const float* r = v.data() + i * stride;
    p.p_lidar = Eigen::Vector3f(r[0], r[1], r[2]);
    p.intensity = stride == 4 ? r[3] : 0.f;
    p.time_offset_s = times.empty() ? 0.f : times[i];
    p.ring = -1;
  }
  return scan;
}

void synthAzimuthTimes(LidarScan& scan, double period_s) {
  constexpr double kTwoPi = 6.283185307179586;
  std::vector<double> az(scan.points.size(), std::nan(""));
  std::vector<double> steps;
  double prev = std::nan("");
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    const Eigen::Vector3f& p = scan.points[i].p_lidar;
    if (!p.allFinite()) continue;
    az[i] = std::atan2(static_cast<double>(p.y()), static_cast<double>(p.x()));
    if (!std::isnan(prev)) steps.push_back(std::remainder(az[i] - prev, kTwoPi));  // wrapped to [-pi, pi]
    prev = az[i];
  }
  double sign = 1.0;
  if (!steps.empty()) {
    auto mid = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
    std::nth_element(steps.begin(), mid, steps.end());
    sign = *mid < 0 ? -1.0 : 1.0;
  }
  double az0 = std::nan("");
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    if (std::isnan(az[i])) {
      scan.points[i].time_offset_s = 0.f;
      continue;
    }
    if (std::isnan(az0)) az0 = az[i];
    double frac = sign * (az[i] - az0) / kTwoPi;
    frac -= std::floor(frac);  // [0, 1)
    scan.points[i].time_offset_s = static_cast<float>(period_s * frac);
  }
}

}  // namespace livo
