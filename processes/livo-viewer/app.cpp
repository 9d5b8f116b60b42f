#include "app.hpp"

#include "livo/cli/command_line.hpp"
#include "livo/common/timing.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/stop_signal.hpp"
#include "livo/process/viewer_node.hpp"
#include "livo/viewer/inset.hpp"
#include "livo/viewer/run_directory.hpp"
#include "livo/viewer/screenshot.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

namespace livo_viewer {

using namespace livo::viewer;
using livo::kExitOk;
using livo::kExitRunError;

namespace {

constexpr int kInsetWidth = 320;  // camera inset, pixels

/// The window and what it shows: draws what changed each frame, places the view camera, handles the
/// keys, takes screenshots.
class Window {
 public:
  Window(const Options& opt, std::string source, const SceneConfig& scene_cfg)
      : opt_(opt), source_(std::move(source)), scene_(scene_cfg), renderer_(opt.renderer), view_(opt.view),
        colour_(opt.colour) {
    if (!scene_cfg.have_intensity && colour_ == ColourMode::kIntensity) colour_ = ColourMode::kImage;
  }

  Scene& scene() { return scene_; }
  void setImage(const livo::Image& gray) { renderer_.setImage(shrinkGray8(gray, kInsetWidth)); }

  /// Draws what changed, handles the keys and events for up to `spin_ms`. False once the window closed.
  bool frame(int spin_ms) {
    const double t0 = clock_.elapsedMs();
    handleKeys();
    draw(false);
    const double t1 = clock_.elapsedMs();
    const bool open = renderer_.spinOnce(spin_ms);
    draw_ms_ += t1 - t0;
    render_ms_ += clock_.elapsedMs() - t1;
    ++frames_;
    return open;
  }
  /// "N frames drawn, mean D ms to update the scene + R ms to render".
  std::string drawingSummary() const {
    char buf[128];
    const double n = frames_ ? double(frames_) : 1.0;
    std::snprintf(buf, sizeof buf, "%lu frames drawn, mean %.1f ms to update the scene + %.1f ms to render", frames_,
                  draw_ms_ / n, render_ms_ / n);
    return buf;
  }

  bool screenshotDue() const {
    return opt_.screenshot_at_s >= 0.0 && !scene_.track().empty() && scene_.elapsedS() >= opt_.screenshot_at_s;
  }

  /// Draws everything and writes `path` and its sidecar (.json).
  void screenshot(const std::string& path) {
    draw(true);
    ScreenshotInfo info = renderer_.saveScreenshot(path);
    info.view = viewModeName(view_);
    info.colour = colourModeName(colour_);
    info.poses = scene_.track().poses().size();
    info.map_points = drawn_map_points_;
    if (!scene_.track().empty()) {
      info.first_utime = scene_.track().poses().front().utime;
      info.last_utime = scene_.track().last().utime;
    }
    info.message_time_s = scene_.elapsedS();
    const std::string json = sidecarPath(path);
    std::ofstream f(json);
    if (!(f << screenshotJson(info))) throw std::runtime_error(json + ": cannot write");
    std::fprintf(stderr, "livo-viewer: screenshot %s (%dx%d, %zu poses, %zu map points, t %.2f s) + %s\n",
                 path.c_str(), info.width, info.height, info.poses, info.map_points, info.message_time_s,
                 json.c_str());
  }

 private:
  void handleKeys() {
    for (const char k : renderer_.takeKeys()) {
      if (k == 'v') {
        view_ = nextViewMode(view_);
        follow_.reset();
      } else if (k == 'b') {
        colour_ = nextColourMode(colour_, scene_.config().have_intensity);
        force_map_ = true;
      } else if (k == 'n') {
        scene_.clear();
        view_ = ViewMode::kFollow;
        follow_.reset();
      } else if (k == 'k') {
        std::string path;
        for (int n = ++shots_; path.empty() || std::filesystem::exists(path); ++n)
          path = "livo-viewer-" + std::to_string(n) + ".png";
        try {
          screenshot(path);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "livo-viewer: %s\n", e.what());
        }
      }
    }
  }

  void draw(bool everything) {
    const double now_s = clock_.elapsedMs() / 1000.0;
    const bool map_changed = scene_.map().version() != map_version_ || force_map_;
    if (map_changed && (everything || force_map_ || now_s - last_map_draw_s_ >= opt_.map_refresh_s)) {
      const ColouredPoints pts = scene_.mapPoints(colour_);
      renderer_.setMap(pts);
      robustBounds(pts.xyz, 0.005, map_lo_, map_hi_);
      drawn_map_points_ = pts.xyz.size();
      map_version_ = scene_.map().version();
      last_map_draw_s_ = now_s;
      force_map_ = false;
    }
    if (scene_.scanVersion() != scan_version_) {
      renderer_.setScan(scene_.scanPoints());
      scan_version_ = scene_.scanVersion();
    }
    if (scene_.track().version() != track_version_) {
      renderer_.setTrajectory(scene_.track().poses());
      track_version_ = scene_.track().version();
    }
    if (scene_.mapFrameVersion() != map_frame_version_) {
      renderer_.setMapFrame(scene_.mapFramePath(), scene_.loopEdges());
      map_frame_version_ = scene_.mapFrameVersion();
    }
    std::optional<std::array<livo::Vec3, 5>> frustum;
    if (opt_.intrinsics.valid() && !scene_.track().empty())
      frustum = frustumCorners(opt_.intrinsics, scene_.track().last().T_world_imu * opt_.T_imu_camera,
                               opt_.frustum_depth_m);
    renderer_.setFrustum(frustum);
    const std::string text = overlayText(scene_.overlay(source_, view_, colour_));
    overlay_lines_ = 1 + std::count(text.begin(), text.end(), '\n');
    renderer_.setText(text);
    placeCamera();
  }

  void placeCamera() {
    const auto& track = scene_.track();
    if (view_ == ViewMode::kFollow && !track.empty()) {
      renderer_.setCamera(follow_.update(track.last().T_world_imu, livo::toSeconds(track.last().utime)));
    } else if (view_ == ViewMode::kTop && (!track.empty() || drawn_map_points_ > 0)) {
      livo::Vec3 lo = map_lo_, hi = map_hi_;
      if (drawn_map_points_ == 0) lo = hi = track.minCorner();
      if (!track.empty()) {
        lo = lo.cwiseMin(track.minCorner());
        hi = hi.cwiseMax(track.maxCorner());
      }
      // The text overlay's lines (font 14 px + spacing) stay above the map.
      const double text_px = 20.0 + 17.0 * double(overlay_lines_);
      renderer_.setCamera(topCamera(lo, hi, double(opt_.renderer.width) / double(opt_.renderer.height), 0.04,
                                    text_px / double(opt_.renderer.height)));
    }
  }

  const Options& opt_;
  std::string source_;
  Scene scene_;
  Renderer renderer_;
  ViewMode view_;
  ColourMode colour_;
  FollowCamera follow_;
  livo::Stopwatch clock_;  // wall clock: only how often the map is re-sent to VTK
  std::uint64_t map_version_ = ~0ull, scan_version_ = ~0ull, track_version_ = ~0ull, map_frame_version_ = 0;
  double last_map_draw_s_ = -1e9;
  bool force_map_ = false;
  std::size_t drawn_map_points_ = 0;
  livo::Vec3 map_lo_ = livo::Vec3::Zero(), map_hi_ = livo::Vec3::Zero();
  int shots_ = 0;
  long overlay_lines_ = 6;
  unsigned long frames_ = 0;
  double draw_ms_ = 0.0, render_ms_ = 0.0;
};

/// Takes the requested screenshot at the end when its time never came; false when nothing was drawn.
bool screenshotAtEnd(const Options& opt, Window& w) {
  if (w.scene().track().empty() && w.scene().map().size() == 0) {
    std::fprintf(stderr, "livo-viewer: error: nothing to draw (no pose arrived), no screenshot written\n");
    return false;
  }
  std::fprintf(stderr, "livo-viewer: the stream ended at t %.2f s, before --screenshot-at %.2f s: taking it now\n",
               w.scene().elapsedS(), opt.screenshot_at_s);
  w.screenshot(opt.screenshot_path);
  return true;
}

}  // namespace

int runLive(const Options& opt) {
  Inbox inbox(opt.scan_queue);
  livo::LcmNode lcm(opt.lcm_url, "livo-viewer", &std::cerr);
  livo::ViewerNode node(lcm, opt.channels, inbox, opt.camera);
  Window w(opt, "livo-viewer: live on " + opt.lcm_url, opt.scene);
  std::fprintf(stderr, "livo-viewer: %s on %s\n", node.channelList().c_str(), opt.lcm_url.c_str());

  // The message thread: reads and converts everything, never waits for the drawing (Inbox drops).
  std::atomic<bool> stream_ended{false};
  std::thread rx([&] {
    try {
      lcm.spin(opt.idle_exit_s, [&] { node.syncCounters(); });
    } catch (const std::exception& e) {
      std::fprintf(stderr, "livo-viewer: error: %s\n", e.what());
    }
    stream_ended = true;
  });
  bool shot = false, closed = false;
  while (!livo::stopRequested() && !stream_ended) {
    InboxBatch batch = inbox.take();
    if (batch.image) w.setImage(*batch.image);
    w.scene().apply(std::move(batch));
    if (!w.frame(20)) {
      closed = true;
      break;
    }
    if (w.screenshotDue()) {
      w.screenshot(opt.screenshot_path);
      shot = true;
      break;
    }
  }
  livo::requestStop();
  rx.join();
  int code = kExitOk;
  if (!opt.screenshot_path.empty() && !shot && !closed) {
    w.scene().apply(inbox.take());
    code = screenshotAtEnd(opt, w) ? kExitOk : kExitRunError;
  }
  const DropCounters d = inbox.drops();
  std::fprintf(stderr, "livo-viewer: %llu poses, %zu map points; dropped %llu scans, %llu images; %llu rejected; %s\n",
               static_cast<unsigned long long>(w.scene().track().added()), w.scene().map().size(),
               static_cast<unsigned long long>(d.scans), static_cast<unsigned long long>(d.images),
               static_cast<unsigned long long>(d.rejected), w.drawingSummary().c_str());
  return code;
}

int runDirectory(const Options& opt, const RunDirectory& run) {
  std::fprintf(stderr, "livo-viewer: %s: %zu poses; %s\n", opt.run_dir.c_str(), run.poses.size(), run.map_note.c_str());
  SceneConfig sc = opt.scene;
  sc.have_intensity = false;
  Window w(opt, "livo-viewer: run " + opt.run_dir, sc);
  // map.pcd at once; more points than the map holds: every k-th, evenly over the file.
  const std::size_t n = run.map.points.size(), cap = sc.map.max_points;
  if (n > cap) {
    ScanInput sub;
    const std::size_t k = (n + cap - 1) / cap;
    for (std::size_t i = 0; i < n; i += k) {
      sub.points.push_back(run.map.points[i]);
      if (!run.map.rgb.empty()) sub.rgb.push_back(run.map.rgb[i]);
    }
    std::fprintf(stderr, "livo-viewer: drawing every %zu-th of %zu map points (--max-points %zu)\n", k, n, cap);
    w.scene().addMapPoints(sub);
  } else {
    w.scene().addMapPoints(run.map);
  }
  // The trajectory at opt.speed times its own time (0: at once); the wall clock only paces it.
  livo::Stopwatch wall;
  std::size_t next = 0;
  const livo::Utime t0 = run.poses.front().utime;
  bool shot = false;
  while (!livo::stopRequested()) {
    InboxBatch batch;
    const double until_s = opt.speed > 0.0 ? opt.speed * wall.elapsedMs() / 1000.0 : 1e300;
    while (next < run.poses.size() && livo::toSeconds(run.poses[next].utime - t0) <= until_s)
      batch.poses.push_back(run.poses[next++]);
    w.scene().apply(std::move(batch));
    if (!w.frame(20)) break;
    if (!opt.screenshot_path.empty() && !shot && (w.screenshotDue() || next == run.poses.size())) {
      w.screenshot(opt.screenshot_path);
      shot = true;
      break;
    }
  }
  std::fprintf(stderr, "livo-viewer: %s\n", w.drawingSummary().c_str());
  return kExitOk;
}

}  // namespace livo_viewer
