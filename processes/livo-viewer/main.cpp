// livo-viewer [--config CFG.yaml] [--lcm-url URL] [--idle-exit S] [--camera] [--view follow|top|free]
//             [--colour height|intensity|image] [--voxel M] [--max-points N] [--clip-above M]
//             [--screenshot-at S FILE] [--print-config]
// livo-viewer --run DIR [--speed X] [...]
//
// A live 3D view of a running suite (LIVO_REGISTERED_SCAN, LIVO_ODOMETRY, LIVO_ESTIMATOR_STATS,
// LIVO_MAP_STATS, with --camera LIVO_CAMERA), or the replay of a run directory (trajectory.tum +
// map.pcd), on PCL's visualisation module. It only listens: it never publishes, and a message thread
// that never waits for the drawing keeps reading the socket (what cannot be drawn is dropped, counted).
#include "app.hpp"

#include "livo/cli/command_line.hpp"
#include "livo/common/config.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/stop_signal.hpp"
#include "livo/sensors/camera_config.hpp"

#include <iostream>

using namespace livo;

namespace {

struct Args {
  std::string config, lcm_url, run_dir, view = "follow", colour = "height", screenshot_file;
  double idle_exit_s = 0.0, voxel_m = 0.1, clip_above_m = 1.0, speed = 1.0, screenshot_at_s = -1.0;
  double point_size = 2.0, frustum_depth_m = 0.6;
  std::int64_t max_points = 400'000, scan_queue = 8, width = 1280, height = 800;
  bool camera = false, print_config = false;
};

void addOptions(CommandLine& cl, Args& a) {
  cl.text("--run", &a.run_dir, "DIR", "replay a run directory (trajectory.tum + map.pcd) instead of listening");
  cl.text("--config", &a.config, "CFG.yaml",
          "rig config: channel names (section channels) and the camera (section camera) for the frustum")
      .defaultText("none: default channels, no frustum");
  cl.text("--lcm-url", &a.lcm_url, "URL", "LCM URL").defaultText(std::string("$LCM_DEFAULT_URL, else ") + kDefaultLcmUrl);
  cl.number("--idle-exit", &a.idle_exit_s, "S", "exit after S seconds without any message (0: never)", 0.0).unit("s");
  cl.flag("--camera", &a.camera, "also subscribe to the camera channel and show the latest image in a corner");
  cl.choice("--view", &a.view, {"follow", "top", "free"},
            "camera at start: follow (behind the latest pose), top (straight down over everything), free (mouse)");
  cl.choice("--colour", &a.colour, {"height", "intensity", "image"}, "map colours at start");
  cl.number("--voxel", &a.voxel_m, "M", "voxel of the accumulated map: one drawn point per voxel", 0.0, true).unit("m");
  cl.integer("--max-points", &a.max_points, "N", "map points drawn; beyond, the least recently seen voxels go", 1,
             100'000'000);
  cl.number("--clip-above", &a.clip_above_m, "M",
            "points higher than the highest pose + M are not drawn (a ceiling hides the room; 0: draw all)", 0.0)
      .unit("m");
  cl.number("--point-size", &a.point_size, "PX", "map point size", 1.0).unit("px");
  cl.number("--frustum-depth", &a.frustum_depth_m, "M", "depth of the drawn camera frustum", 0.0, true).unit("m");
  cl.integer("--width", &a.width, "PX", "window width", 64, 8192);
  cl.integer("--height", &a.height, "PX", "window height", 64, 8192);
  cl.integer("--scan-queue", &a.scan_queue, "N", "scans waiting for the drawing loop; older ones are dropped (counted)",
             1, 1000);
  cl.number("--speed", &a.speed, "X", "--run: replay at X times the trajectory's time (0: all at once)", 0.0);
  cl.number("--screenshot-at", &a.screenshot_at_s, "S",
            "write FILE (PNG; FILE.json: the camera matrix and what is drawn) once S seconds of message time "
            "have passed since the first pose (or when the stream or the replay ends before), then exit",
            0.0)
      .unit("s")
      .defaultText("none")
      .andText("FILE", &a.screenshot_file);
  cl.flag("--print-config", &a.print_config, kPrintConfigHelp);
  cl.epilog(
      "keys: v view (follow / top / free), b colour (height / intensity / image), n reset (forget the map and\n"
      "the trajectory), k screenshot (livo-viewer-N.png + .json), q quit; mouse: rotate, zoom, pan (free view);\n"
      "PCL's own keys stay (h help, +/- point size, r fit all, j PCL's snapshot).");
}

/// Channels and the camera's frustum from the config (all defaults without one).
ConfigFile loadConfig(const Args& a, livo_viewer::Options& opt) {
  ConfigFile file = a.config.empty() ? ConfigFile::parse("{}", "<defaults>") : ConfigFile::load(a.config);
  const ConfigNode root = file.root();
  opt.channels.load(root.section("channels"));
  CameraConfig cam;
  cam.load(root);
  if (cam.enabled) {
    opt.intrinsics = {cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy};
    opt.T_imu_camera = cam.T_imu_camera;
  }
  checkSectionsUsed(file, {"channels"});
  return file;
}

livo_viewer::Options toOptions(const Args& a) {
  livo_viewer::Options opt;
  opt.run_dir = a.run_dir;
  opt.idle_exit_s = a.idle_exit_s;
  opt.camera = a.camera;
  opt.frustum_depth_m = a.frustum_depth_m;
  opt.scene.map.voxel_m = a.voxel_m;
  opt.scene.map.max_points = static_cast<std::size_t>(a.max_points);
  opt.scene.clip_above_m = a.clip_above_m;
  opt.scan_queue = static_cast<std::size_t>(a.scan_queue);
  viewer::parseViewMode(a.view, opt.view);
  viewer::parseColourMode(a.colour, opt.colour);
  opt.speed = a.speed;
  opt.screenshot_at_s = a.screenshot_at_s;
  opt.screenshot_path = a.screenshot_file;
  opt.renderer.width = static_cast<int>(a.width);
  opt.renderer.height = static_cast<int>(a.height);
  opt.renderer.point_size = a.point_size;
  return opt;
}

}  // namespace

int main(int argc, char** argv) {
  installStopHandlers();
  Args a;
  CommandLine cl("livo-viewer",
                 "Shows a running suite live (accumulated map, current scan, trajectory, camera frustum, figures),\n"
                 "or replays a run directory (--run DIR). Needs an X display (xvfb-run for a headless machine).");
  addOptions(cl, a);
  if (const auto code = cl.parseOrExit(argc, argv)) return *code;

  livo_viewer::Options opt = toOptions(a);
  try {
    const ConfigFile file = loadConfig(a, opt);
    if (a.print_config) {
      printConfig(std::cout, cl.program(), file);
      return kExitOk;
    }
  } catch (const std::exception& e) {
    std::cerr << "livo-viewer: " << e.what() << "\n";
    return kExitUsage;
  }
  try {
    // A bad run directory is reported before the display is looked at.
    viewer::RunDirectory run;
    if (!opt.run_dir.empty()) run = viewer::loadRunDirectory(opt.run_dir);
    if (const std::string why = livo_viewer::displayProblem(); !why.empty()) {
      std::cerr << "livo-viewer: " << why << "\n";
      return kExitRunError;
    }
    if (!opt.run_dir.empty()) return livo_viewer::runDirectory(opt, run);
    opt.lcm_url = resolveLcmUrl(a.lcm_url);
    return livo_viewer::runLive(opt);
  } catch (const std::exception& e) {
    std::cerr << "livo-viewer: error: " << e.what() << "\n";
    return kExitRunError;
  }
}
