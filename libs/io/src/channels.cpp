#include "livo/io/channels.hpp"

#include <cstdlib>

namespace livo {

void ChannelConfig::load(const ConfigNode& n) {
  n.get("imu", imu).get("lidar", lidar).get("camera", camera).get("frame", frame);
  n.get("map_query", map_query).get("submap", submap).get("map_update", map_update);
  n.get("odometry", odometry).get("registered_scan", registered_scan);
  n.get("estimator_stats", estimator_stats).get("map_stats", map_stats);
  n.get("filter_state", filter_state).get("resume_request", resume_request).get("resume", resume);
  n.get("map_correction", map_correction);
  for (const std::string* c : {&imu, &lidar, &camera, &frame, &map_query, &submap, &map_update, &odometry,
                               &registered_scan, &estimator_stats, &map_stats, &filter_state, &resume_request,
                               &resume, &map_correction})
    n.check(!c->empty() && c->size() < 256, "channels", "channel names must be 1..255 characters");
}

std::string resolveLcmUrl(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env && *env) return env;
  return kDefaultLcmUrl;
}

}  // namespace livo
