// LCM channel names (config section `channels`; defaults as in the suite's contract) and the default URL.
#pragma once

#include "livo/common/config.hpp"

#include <string>

namespace livo {

/// Default LCM URL: multicast on the host only (ttl=0) with a 4 MB receive buffer for large messages.
inline const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

struct ChannelConfig {
  std::string imu = "LIVO_IMU";
  std::string lidar = "LIVO_LIDAR";
  std::string camera = "LIVO_CAMERA";
  std::string frame = "LIVO_FRAME";
  std::string map_query = "LIVO_MAP_QUERY";
  std::string submap = "LIVO_SUBMAP";
  std::string map_update = "LIVO_MAP_UPDATE";
  std::string odometry = "LIVO_ODOMETRY";
  std::string registered_scan = "LIVO_REGISTERED_SCAN";
  std::string estimator_stats = "LIVO_ESTIMATOR_STATS";
  std::string map_stats = "LIVO_MAP_STATS";
  // Restarts: the estimator's filter state after each frame (kept by the map server), a starting
  // estimator's request for it and the map server's answer (livo/io/resume_messages.hpp).
  std::string filter_state = "LIVO_FILTER_STATE";
  std::string resume_request = "LIVO_RESUME_REQUEST";
  std::string resume = "LIVO_RESUME";
  // Loop closure: livo-loop's map frame (livo/io/loop_messages.hpp).
  std::string map_correction = "LIVO_MAP_CORRECTION";

  /// Reads the `channels` section.
  void load(const ConfigNode& channels);
};

/// The URL to use: the --lcm-url flag if given, else $LCM_DEFAULT_URL, else kDefaultLcmUrl.
std::string resolveLcmUrl(const std::string& flag);

}  // namespace livo
