#include "livo/viewer/run_directory.hpp"

#include "livo/eval/tum.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace livo::viewer {

namespace fs = std::filesystem;

namespace {

/// The header of a PCD file (v0.7) checked before PCL reads it: PCL 1.13's reader crashes on some
/// malformed files (a header without its size lines, fields without x / y / z) instead of failing.
/// Throws std::runtime_error naming the file and the problem; returns the field names.
std::vector<std::string> checkPcdHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  const auto bad = [&](const std::string& what) { throw std::runtime_error(path + ": not a PCD file (" + what + ")"); };
  std::map<std::string, std::vector<std::string>> h;
  std::string line;
  std::size_t header_bytes = 0;
  for (int n = 1; std::getline(in, line); ++n) {
    header_bytes += line.size() + 1;
    if (header_bytes > 65536) bad("no DATA line in the first 64 KiB");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string key;
    words >> key;
    static const char* kKeys[] = {"VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT",
                                  "POINTS", "DATA"};
    if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys))
      bad("line " + std::to_string(n) + ": unknown header line '" + line.substr(0, 40) + "'");
    for (std::string w; words >> w;) h[key].push_back(w);
    if (key == "DATA") break;
  }
  for (const char* k : {"FIELDS", "SIZE", "TYPE", "WIDTH", "DATA"})
    if (h[k].empty()) bad(std::string("no ") + k + " line");
  const std::size_t nf = h["FIELDS"].size();
  if (h["SIZE"].size() != nf || h["TYPE"].size() != nf || (!h["COUNT"].empty() && h["COUNT"].size() != nf))
    bad("FIELDS, SIZE, TYPE and COUNT differ in length");
  std::size_t point_bytes = 0;
  for (std::size_t i = 0; i < nf; ++i) {
    const std::string& size = h["SIZE"][i];
    const std::string& type = h["TYPE"][i];
    const std::string count = h["COUNT"].empty() ? "1" : h["COUNT"][i];
    if (!(size == "1" || size == "2" || size == "4" || size == "8") || !(type == "F" || type == "I" || type == "U") ||
        count.empty() || count.find_first_not_of("0123456789") != std::string::npos || count.size() > 6)
      bad("field " + h["FIELDS"][i] + ": SIZE " + size + ", TYPE " + type + ", COUNT " + count);
    point_bytes += std::stoul(size) * std::stoul(count);
  }
  const auto number = [&](const char* k, const std::string& dflt) {
    const std::string v = h[k].empty() ? dflt : h[k][0];
    if (v.empty() || v.size() > 12 || v.find_first_not_of("0123456789") != std::string::npos)
      bad(std::string(k) + " '" + v + "' is not a count");
    return std::stoull(v);
  };
  const std::uint64_t points = number("WIDTH", "") * number("HEIGHT", "1");
  if (!h["POINTS"].empty() && number("POINTS", "") != points) bad("POINTS differs from WIDTH x HEIGHT");
  const std::string data = h["DATA"][0];
  if (data != "ascii" && data != "binary" && data != "binary_compressed") bad("DATA '" + data + "'");
  const std::uint64_t body = fs::file_size(path) - std::min<std::uint64_t>(fs::file_size(path), header_bytes);
  if (data == "binary" && body < points * point_bytes)
    throw std::runtime_error(path + ": truncated PCD (" + std::to_string(body) + " bytes of data for " +
                             std::to_string(points) + " points of " + std::to_string(point_bytes) + " bytes)");
  if (data == "binary_compressed" && points > 0 && body < 8)
    throw std::runtime_error(path + ": truncated PCD (no compressed data)");
  return h["FIELDS"];
}

}  // namespace

ScanInput loadPcdPoints(const std::string& path, std::string* fields) {
  pcl::PCLPointCloud2 blob;
  pcl::PCDReader reader;
  if (!fs::is_regular_file(path)) throw std::runtime_error(path + ": no such file");
  const std::vector<std::string> names = checkPcdHeader(path);
  const auto has = [&](const char* f) { return std::find(names.begin(), names.end(), f) != names.end(); };
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : " ") + n;
  if (!(has("x") && has("y") && has("z")))
    throw std::runtime_error(path + ": PCD without x, y, z fields (has: " + list + ")");
  if (fields) *fields = list;
  // read() returns < 0 for data it cannot parse (it also prints PCL's own reason on stderr).
  if (reader.read(path, blob) < 0) throw std::runtime_error(path + ": PCL could not read the PCD data");
  const bool has_rgb = has("rgb") || has("rgba");
  ScanInput out;
  if (has_rgb) {
    pcl::PointCloud<pcl::PointXYZRGB> cloud;
    pcl::fromPCLPointCloud2(blob, cloud);
    out.points.reserve(cloud.size());
    out.rgb.reserve(cloud.size());
    for (const auto& p : cloud) {
      out.points.emplace_back(p.x, p.y, p.z);
      out.rgb.push_back(std::int32_t((std::uint32_t(p.r) << 16) | (std::uint32_t(p.g) << 8) | p.b));
    }
  } else {
    pcl::PointCloud<pcl::PointXYZ> cloud;
    pcl::fromPCLPointCloud2(blob, cloud);
    out.points.reserve(cloud.size());
    for (const auto& p : cloud) out.points.emplace_back(p.x, p.y, p.z);
  }
  return out;
}

RunDirectory loadRunDirectory(const std::string& dir) {
  if (!fs::is_directory(dir)) throw std::runtime_error(dir + ": no such directory");
  const std::string tum = (fs::path(dir) / "trajectory.tum").string();
  if (!fs::is_regular_file(tum))
    throw std::runtime_error(tum + ": missing (not a livo-run / livo-exporter output directory?)");
  RunDirectory run;
  for (const StampedPose& p : readTum(tum)) run.poses.push_back(PoseInput{fromSeconds(p.t), p.T_world_body, false});
  const std::string pcd = (fs::path(dir) / "map.pcd").string();
  if (!fs::exists(pcd)) {
    run.map_note = "map.pcd: none (a run with --no-maps?): trajectory only";
    return run;
  }
  std::string fields;
  run.map = loadPcdPoints(pcd, &fields);
  run.has_map = true;
  run.map_note = "map.pcd: " + std::to_string(run.map.points.size()) + " points (" + fields + ")";
  return run;
}

}  // namespace livo::viewer
