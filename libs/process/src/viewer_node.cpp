#include "livo/process/viewer_node.hpp"

#include "livo/io/estimator_messages.hpp"
#include "livo/io/image_convert.hpp"
#include "livo/io/loop_messages.hpp"
#include "livo/io/map_messages.hpp"

namespace livo {

ViewerNode::ViewerNode(LcmNode& lcm, const ChannelConfig& channels, viewer::Inbox& inbox, bool camera)
    : lcm_(lcm), inbox_(inbox) {
  lcm_.subscribeStruct<livo::registered_scan_t, RegisteredScan>(channels.registered_scan, [this](RegisteredScan& s) {
    inbox_.pushScan(viewer::ScanInput{s.utime, std::move(s.points), std::move(s.intensity), std::move(s.rgb)});
  });
  lcm_.subscribeStruct<livo::odometry_t, OdometryOutput>(channels.odometry, [this](OdometryOutput& o) {
    if (o.status & odometry_status::kInitializing) return;  // no pose yet
    inbox_.pushPose(viewer::PoseInput{o.utime, o.state.pose(), (o.status & odometry_status::kDegenerate) != 0});
  });
  lcm_.subscribeStruct<livo::estimator_stats_t, EstimatorStats>(channels.estimator_stats, [this](EstimatorStats& s) {
    viewer::FrameStatsInput f;
    f.utime = s.utime;
    f.total_ms = s.total_ms;
    f.lio_ms = s.lio_ms;
    f.vio_ms = s.vio_ms;
    f.sigma_min = s.sigma_min;
    f.degenerate = s.degenerate;
    f.visual_used = s.visual_used;
    f.map_timeout = s.map_timeout;
    f.health = s.health;
    f.health_reason = s.health_reason;
    inbox_.pushFrameStats(f);
  });
  lcm_.subscribeStruct<livo::map_stats_t, MapStats>(channels.map_stats, [this](MapStats& m) {
    inbox_.pushMapStats(viewer::MapStatsInput{m.utime, m.bytes, m.bytes_cap, m.local_voxels,
                                              m.visual_points_local + m.visual_points_longterm});
  });
  lcm_.subscribeStruct<livo::map_correction_t, MapCorrection>(channels.map_correction, [this](MapCorrection& c) {
    inbox_.pushCorrection(std::move(c));
  });
  channels_ = {channels.registered_scan, channels.odometry, channels.estimator_stats, channels.map_stats,
               channels.map_correction};
  if (camera) {
    lcm_.subscribe<livo::image_t>(channels.camera, [this](const livo::image_t& m) {
      Image img, gray;
      Validation v = fromMsg(m, img, lcm_.limits());
      std::string err;
      if (v && !toGray8(std::move(img), gray, &err)) v = Validation::fail(err);
      if (v) inbox_.pushImage(std::move(gray));
      return v;
    });
    channels_.push_back(channels.camera);
  }
}

void ViewerNode::syncCounters() { inbox_.setRejected(lcm_.totalRejected()); }

std::string ViewerNode::channelList() const {
  std::string s;
  for (const auto& c : channels_) s += (s.empty() ? "" : " + ") + c;
  return s;
}

}  // namespace livo
