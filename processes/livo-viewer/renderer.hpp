// livo-viewer's window, on PCL's visualisation module (PCLVisualizer over VTK): the map and the current
// scan as point clouds, the trajectory and the camera frustum as lines, the text overlay, the camera
// inset, the view camera and screenshots with their sidecar. The only file of the viewer that sees PCL's
// visualiser or VTK; what is drawn comes from libs/viewer.
#pragma once

#include "livo/common/types.hpp"
#include "livo/viewer/geometry.hpp"
#include "livo/viewer/scene.hpp"
#include "livo/viewer/screenshot.hpp"

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace livo_viewer {

struct RendererOptions {
  int width = 1280, height = 800;  ///< window size, pixels
  double point_size = 2.0;         ///< map points, pixels (the scan is drawn one pixel larger)
  double line_width = 3.0;         ///< trajectory, pixels
  std::string title = "livo-viewer";
};

/// Why there is no window: "" when an X display can be opened, else a sentence naming $DISPLAY.
std::string displayProblem();

class Renderer {
 public:
  /// Opens the window. Throws std::runtime_error when no X display can be opened (check
  /// displayProblem() first for a clean message).
  explicit Renderer(const RendererOptions& opt);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  void setMap(const livo::viewer::ColouredPoints& pts);
  void setScan(const livo::viewer::ColouredPoints& pts);
  void setTrajectory(const std::vector<livo::viewer::PoseInput>& poses);
  /// The loop closure's corrected keyframe path (a line) and its loop edges (segments).
  void setMapFrame(const std::vector<livo::Vec3>& path, const std::vector<std::pair<livo::Vec3, livo::Vec3>>& loops);
  /// The frustum lines (frustumCorners()); nullopt hides it.
  void setFrustum(const std::optional<std::array<livo::Vec3, 5>>& corners);
  void setText(const std::string& text);
  /// The camera inset (a Gray8 image, drawn in the top-right corner); nullopt hides it.
  void setImage(const std::optional<livo::Image>& gray);
  void setCamera(const livo::viewer::ViewCamera& cam);

  /// Handles window events for up to `ms` and redraws. False once the window was closed (or 'q').
  bool spinOnce(int ms);
  /// Key codes pressed since the last call.
  std::vector<char> takeKeys();
  /// Draws and writes the window as PNG; returns its size and the camera's world-to-NDC matrix.
  /// Throws std::runtime_error naming the path when it cannot be written.
  livo::viewer::ScreenshotInfo saveScreenshot(const std::string& png_path);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace livo_viewer
