// livo-viewer's message side: subscribes on an LcmNode to LIVO_REGISTERED_SCAN, LIVO_ODOMETRY,
// LIVO_ESTIMATOR_STATS, LIVO_MAP_STATS, LIVO_MAP_CORRECTION (livo-loop) and (with `camera`) LIVO_CAMERA, validates and converts each
// message into the viewer's plain inputs (libs/viewer) and pushes it into the Inbox. It never waits
// for the drawing: the LcmNode runs in its own thread and keeps reading the socket, and the Inbox drops
// what the drawing loop has not taken (counted). Rejected messages are counted into the Inbox too.
#pragma once

#include "livo/io/channels.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/viewer/inbox.hpp"

namespace livo {

class ViewerNode {
 public:
  ViewerNode(LcmNode& lcm, const ChannelConfig& channels, viewer::Inbox& inbox, bool camera);
  /// Copies the LcmNode's reject count into the Inbox; call from the thread that runs the LcmNode
  /// (LcmNode::spin's poll callback).
  void syncCounters();
  /// Channels subscribed to, for the start-up line ("LIVO_REGISTERED_SCAN + LIVO_ODOMETRY + ...").
  std::string channelList() const;

 private:
  LcmNode& lcm_;
  viewer::Inbox& inbox_;
  std::vector<std::string> channels_;
};

}  // namespace livo
