// livo-viewer's two ways to run (main.cpp parses the command line into Options): live over LCM, or the
// replay of a run directory. Both feed a libs/viewer Scene and draw it with the Renderer.
#pragma once

#include "renderer.hpp"

#include "livo/common/so3.hpp"
#include "livo/io/channels.hpp"
#include "livo/viewer/geometry.hpp"
#include "livo/viewer/run_directory.hpp"
#include "livo/viewer/scene.hpp"

#include <string>

namespace livo_viewer {

struct Options {
  std::string run_dir;            ///< --run DIR: replay it instead of listening
  std::string lcm_url;            ///< resolved URL (live)
  double idle_exit_s = 0.0;       ///< live: exit after this long without any message (0: never)
  bool camera = false;            ///< live: subscribe to the camera for the inset
  livo::ChannelConfig channels;
  livo::viewer::FrustumIntrinsics intrinsics;  ///< from the config's camera section (none: no frustum)
  livo::Pose T_imu_camera = livo::Pose::Identity();
  double frustum_depth_m = 0.6;
  livo::viewer::SceneConfig scene;
  std::size_t scan_queue = 8;     ///< scans waiting for the drawing loop; older ones are dropped
  livo::viewer::ViewMode view = livo::viewer::ViewMode::kFollow;
  livo::viewer::ColourMode colour = livo::viewer::ColourMode::kHeight;
  double map_refresh_s = 0.2;     ///< the map cloud is re-sent to VTK at most this often (wall clock)
  double speed = 1.0;             ///< replay: times real time (0: everything at once)
  double screenshot_at_s = -1.0;  ///< < 0: none
  std::string screenshot_path;
  RendererOptions renderer;
};

/// Listens on opt.lcm_url until SIGINT / SIGTERM, the window is closed, --idle-exit, or the screenshot
/// was taken. Returns the exit code.
int runLive(const Options& opt);
/// Replays a run directory read by loadRunDirectory() (map.pcd at once, the trajectory at opt.speed).
/// Returns the exit code.
int runDirectory(const Options& opt, const livo::viewer::RunDirectory& run);

}  // namespace livo_viewer
