#include "livo/process/preprocess_node.hpp"

#include "livo/common/timing.hpp"

#include "livo/io/image_convert.hpp"

#include <iomanip>
#include <sstream>

namespace livo {

PreprocessNode::PreprocessNode(LcmNode& lcm, const PreprocessConfig& cfg, const ChannelConfig& channels,
                               std::ostream* log, double report_interval_s)
    : lcm_(lcm), channels_(channels), log_(log), report_interval_s_(report_interval_s), recombiner_(cfg) {
  lcm_.subscribe<livo::imu_t>(channels_.imu, [this](const livo::imu_t& m) { return onImu(m); });
  lcm_.subscribe<livo::lidar_scan_t>(channels_.lidar, [this](const livo::lidar_scan_t& m) { return onLidar(m); });
  lcm_.subscribeRaw(channels_.camera, [this](const void* d, std::size_t n) { return onCamera(d, n); });
}

Validation PreprocessNode::onImu(const livo::imu_t& m) {
  ImuSample s;
  Validation v = fromMsg(m, s);
  if (!v) return v;
  recombiner_.addImu(s);
  publishReady();
  return v;
}

Validation PreprocessNode::onLidar(const livo::lidar_scan_t& m) {
  LidarScan scan;
  std::size_t nonfinite = 0;
  Validation v = fromMsg(m, scan, lcm_.limits(), &nonfinite);
  if (!v) return v;
  counters_.nonfinite_points += nonfinite;
  recombiner_.addScan(scan);
  publishReady();
  return v;
}

Validation PreprocessNode::onCamera(const void* data, std::size_t size) {
  if (!recombiner_.config().camera_enabled) {
    recombiner_.addImage(Image{});  // counted as ignored; not even decoded
    return Validation::ok();
  }
  livo::image_t m;
  Image raw, gray;
  Validation v = decode(data, size, m, lcm_.limits());
  if (v) v = fromMsg(std::move(m), raw, lcm_.limits());
  if (!v) return v;
  std::string err;
  if (!toGray8(std::move(raw), gray, &err)) {
    ++counters_.images_unconvertible;
    return Validation::fail("image_t at utime " + std::to_string(m.utime) + ": " + err);
  }
  recombiner_.addImage(std::move(gray));
  publishReady();
  return v;
}

void PreprocessNode::publishReady() {
  Frame f;
  while (recombiner_.nextFrame(f)) {
    try {
      const std::vector<std::uint8_t> buf = encode(toMsg(f));
      lcm_.publishRaw(channels_.frame, buf.data(), buf.size());
      ++counters_.frames_published;
      counters_.bytes_published += buf.size();
      counters_.frames_with_image += f.has_image;
    } catch (const std::exception& e) {
      ++counters_.publish_errors;
      if (log_ && shouldWarn(counters_.publish_errors))
        *log_ << "livo-preprocess: frame at utime " << f.utime << " not published: " << e.what() << "\n";
    }
    counters_.last_frame_utime = f.utime;
    // Periodic counters, on message time (the frame times), never on the wall clock.
    if (!have_report_time_) {
      have_report_time_ = true;
      last_report_utime_ = f.utime;
    } else if (log_ && report_interval_s_ > 0 && toSeconds(f.utime - last_report_utime_) >= report_interval_s_) {
      *log_ << "livo-preprocess: " << progressLine() << "\n";
      last_report_utime_ = f.utime;
      frames_at_last_report_ = counters_.frames_published;
    }
  }
}

void PreprocessNode::finish() {
  recombiner_.flush();
  publishReady();
}

std::string PreprocessNode::progressLine() const {
  const PreprocessStats& s = recombiner_.stats();
  std::ostringstream os;
  os << std::fixed << std::setprecision(3) << "t " << toSeconds(counters_.last_frame_utime) << " s: frames "
     << counters_.frames_published << " (+" << counters_.frames_published - frames_at_last_report_ << ", "
     << counters_.frames_with_image << " with image), in imu " << s.imu_in << " scans " << s.scans_in << " images "
     << s.images_in << ", rejected " << lcm_.totalRejected() << ", dropped images " << s.imagesDropped()
     << " points late " << s.points_late << " overflow " << s.bufferOverflowDrops();
  return os.str();
}

std::string PreprocessNode::summary() const {
  std::ostringstream os;
  os << "frames published " << counters_.frames_published << " (" << counters_.frames_with_image << " with image, "
     << std::fixed << std::setprecision(1) << double(counters_.bytes_published) / 1e6 << " MB), publish errors "
     << counters_.publish_errors << "\n";
  os << "messages:\n" << lcm_.countersSummary();
  os << "non-finite points dropped in conversion " << counters_.nonfinite_points << ", images not convertible "
     << counters_.images_unconvertible << "\n";
  os << "recombiner:\n" << recombiner_.stats().summary() << "\n";
  os << resourceSummary() << "\n";
  return os.str();
}

}  // namespace livo
