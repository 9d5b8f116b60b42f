// EuRoC folder -> LCM log: reads and checks every input before the log is created, then merges the IMU
// and camera streams by time.
#include "livo/datasets/euroc.hpp"
#include "livo/io/convert.hpp"

#include <algorithm>
#include <filesystem>

namespace fs = std::filesystem;

namespace livo {

namespace {
Utime resolveLimit(double s, Utime first_image) {
  return s >= kAbsoluteTimeThreshold_s ? fromSeconds(s) : first_image + fromSeconds(s);
}
}  // namespace

EurocWindow eurocWindow(Utime first_image, Utime last_image, const EurocOptions& opt) {
  if (!(opt.imu_margin_s >= 0)) throw DatasetError("imu margin must be >= 0 s");
  EurocWindow w;
  w.image_begin = opt.start_s ? resolveLimit(*opt.start_s, first_image) : first_image;
  w.image_end = opt.end_s ? resolveLimit(*opt.end_s, first_image) : last_image;
  if (w.image_end < w.image_begin)
    throw DatasetError("time window: end " + std::to_string(toSeconds(w.image_end)) + " s is before start " +
                       std::to_string(toSeconds(w.image_begin)) + " s");
  const Utime margin = fromSeconds(opt.imu_margin_s);
  w.imu_begin = w.image_begin - margin;
  w.imu_end = w.image_end + margin;
  return w;
}

ConversionSummary convertEuroc(const std::string& dir, const std::string& out_log, const EurocOptions& opt) {
  // 1. Inputs: calibration, both tables (all rows checked), image files present.
  const std::string mav = eurocMavDir(dir, opt);
  const EurocCalibration calib = readEurocCalibration(mav, opt);
  const fs::path cam_dir = fs::path(mav) / opt.camera;
  const std::vector<EurocImageEntry> all_images =
      readEurocImageCsv((cam_dir / "data.csv").string(), (cam_dir / "data").string());
  const std::vector<ImuSample> all_imu = readEurocImuCsv((fs::path(mav) / opt.imu / "data.csv").string());

  // 2. Time window (images define it; the IMU gets a margin on both sides).
  const EurocWindow w = eurocWindow(all_images.front().utime, all_images.back().utime, opt);
  std::vector<EurocImageEntry> images;
  for (const auto& e : all_images)
    if (e.utime >= w.image_begin && e.utime <= w.image_end) images.push_back(e);
  std::vector<ImuSample> imu;
  for (const auto& s : all_imu)
    if (s.utime >= w.imu_begin && s.utime <= w.imu_end) imu.push_back(s);
  if (images.empty())
    throw DatasetError((cam_dir / "data.csv").string() + ": no image inside the window " +
                       std::to_string(toSeconds(w.image_begin)) + " .. " + std::to_string(toSeconds(w.image_end)) +
                       " s");

  // 3. Merge by time; at equal times the IMU sample goes first (it is needed to propagate to the image).
  SummaryLogWriter out(out_log);
  std::size_t i_imu = 0, i_img = 0;
  while (i_imu < imu.size() || i_img < images.size()) {
    const bool take_imu = i_img == images.size() || (i_imu < imu.size() && imu[i_imu].utime <= images[i_img].utime);
    if (take_imu) {
      out.write(opt.imu_channel, toMsg(imu[i_imu++]));
      continue;
    }
    const EurocImageEntry& e = images[i_img++];
    const Image img = readGrayImage(e.path, e.utime);
    if (img.width != calib.camera.width || img.height != calib.camera.height)
      throw DatasetError(e.path + ": image is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                         " but sensor.yaml resolution is " + std::to_string(calib.camera.width) + "x" +
                         std::to_string(calib.camera.height));
    out.write(opt.camera_channel, toMsg(img));
    if (opt.progress) opt.progress(i_img, images.size());
  }
  return out.commit();
}

}  // namespace livo
