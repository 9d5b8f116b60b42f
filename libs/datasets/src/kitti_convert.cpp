// KITTI-style folders -> LCM log: finds the scans (flat, dump or single-file layout), pairs per-point time
// files, checks every file size before the log is created, then writes one LIVO_LIDAR event per scan.
#include "livo/datasets/kitti.hpp"
#include "livo/io/convert.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

namespace fs = std::filesystem;

namespace livo {

namespace {

/// "raw_00" -> ("raw_", "00"); "000001" -> ("", "000001").
std::pair<std::string, std::string> splitSeries(const std::string& stem) {
  std::size_t k = stem.size();
  while (k > 0 && std::isdigit(static_cast<unsigned char>(stem[k - 1]))) --k;
  return {stem.substr(0, k), stem.substr(k)};
}

bool startsWith(const std::string& s, const std::string& p) { return s.compare(0, p.size(), p) == 0; }

std::vector<KittiScanFile> listFlat(const fs::path& dir, const std::vector<fs::path>& bins, const KittiOptions& opt) {
  std::vector<KittiScanFile> scans;
  std::set<std::string> series;
  for (const auto& p : bins) {
    const std::string name = p.filename().string();
    if (!opt.times_prefix.empty() && startsWith(name, opt.times_prefix)) continue;
    if (!opt.prefix.empty() && !startsWith(name, opt.prefix)) continue;
    series.insert(splitSeries(p.stem().string()).first);
    KittiScanFile f;
    f.points_path = p.string();
    scans.push_back(f);
  }
  if (scans.empty())
    throw DatasetError(dir.string() + ": no scan .bin files" +
                       (opt.prefix.empty() ? std::string() : " starting with '" + opt.prefix + "'"));
  if (opt.prefix.empty() && series.size() > 1) {
    std::string names;
    for (const auto& s : series) names += (names.empty() ? "" : ", ") + (s.empty() ? "<digits only>" : s + "*");
    throw DatasetError(dir.string() + ": several scan series (" + names + "); choose one with --prefix");
  }
  if (!opt.use_times || opt.times_prefix.empty()) return scans;
  std::size_t with_times = 0;
  for (auto& f : scans) {
    const std::string id = splitSeries(fs::path(f.points_path).stem().string()).second;
    const fs::path t = dir / (opt.times_prefix + id + ".bin");
    if (!id.empty() && fs::is_regular_file(t)) {
      f.times_path = t.string();
      ++with_times;
    }
  }
  if (with_times > 0 && with_times < scans.size())
    for (const auto& f : scans)
      if (f.times_path.empty())
        throw DatasetError(f.points_path + ": no time file " + opt.times_prefix +
                           splitSeries(fs::path(f.points_path).stem().string()).second + ".bin while " +
                           std::to_string(with_times) + " other scans have one (pass --no-times to ignore them)");
  return scans;
}

std::vector<KittiScanFile> listDump(const std::vector<fs::path>& subdirs, const KittiOptions& opt) {
  std::vector<KittiScanFile> scans;
  for (const auto& d : subdirs) {
    KittiScanFile f;
    f.points_path = (d / "points.bin").string();
    if (!fs::is_regular_file(f.points_path)) throw DatasetError(f.points_path + ": missing file");
    const fs::path t = d / "times.bin";
    if (opt.use_times && fs::is_regular_file(t)) f.times_path = t.string();
    scans.push_back(f);
  }
  return scans;
}

}  // namespace

std::vector<KittiScanFile> listKittiScans(const std::string& dir, const KittiOptions& opt) {
  std::error_code ec;
  if (fs::is_regular_file(dir, ec)) return {KittiScanFile{dir, ""}};
  if (!fs::is_directory(dir, ec)) throw DatasetError(dir + ": no such file or directory");
  std::vector<fs::path> bins, subdirs;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().extension() == ".bin") bins.push_back(e.path());
    if (e.is_directory()) subdirs.push_back(e.path());
  }
  std::sort(bins.begin(), bins.end());
  std::sort(subdirs.begin(), subdirs.end());
  if (!bins.empty()) return listFlat(dir, bins, opt);
  if (!subdirs.empty()) return listDump(subdirs, opt);
  throw DatasetError(dir + ": no scans (expected *.bin files or subfolders with points.bin)");
}

ConversionSummary convertKitti(const std::string& dir, const std::string& out_log, const KittiOptions& opt) {
  if (!(opt.rate_hz > 0) || !std::isfinite(opt.rate_hz)) throw DatasetError("--rate-hz must be positive");
  if (!std::isfinite(opt.start_time_s) || opt.start_time_s < 0)
    throw DatasetError("--start-time must be a non-negative number of seconds");
  // 1. Inputs: the scan list and one record layout that fits every file (all sizes checked up front).
  const std::vector<KittiScanFile> scans = listKittiScans(dir, opt);
  const PointFields fields = resolvePointFields(scans, opt.fields);

  // 2. One event per scan: utime = start + i / rate.
  SummaryLogWriter out(out_log);
  const Utime t0 = fromSeconds(opt.start_time_s);
  const double period_s = 1.0 / opt.rate_hz;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const Utime utime = t0 + static_cast<Utime>(std::llround(static_cast<double>(i) * 1e6 / opt.rate_hz));
    LidarScan scan = readKittiScan(scans[i], fields, utime, opt.sensor);
    if (scans[i].times_path.empty() && opt.synth_times == SynthTimes::Azimuth) synthAzimuthTimes(scan, period_s);
    out.write(opt.lidar_channel, toMsg(scan));
    if (opt.progress) opt.progress(i + 1, scans.size());
  }
  return out.commit();
}

}  // namespace livo
