#include "renderer.hpp"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/visualization/pcl_visualizer.h>

#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkImageData.h>
#include <vtkImageMapper.h>
#include <vtkMatrix4x4.h>
#include <vtkPNGWriter.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkRendererCollection.h>
#include <vtkSmartPointer.h>
#include <vtkWindowToImageFilter.h>

#include <X11/Xlib.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <stdexcept>

namespace livo_viewer {

using livo::viewer::ColouredPoints;
using livo::viewer::Rgb;

std::string displayProblem() {
  const char* name = std::getenv("DISPLAY");
  if (name == nullptr || *name == '\0')
    return "no X display: DISPLAY is not set (run on a desktop, over ssh -X, or under xvfb-run)";
  Display* d = XOpenDisplay(name);
  if (d == nullptr)
    return std::string("cannot open the X display '") + name + "' (is the X server running? xvfb-run starts one)";
  XCloseDisplay(d);
  return "";
}

namespace {

constexpr const char* kMapId = "map";
constexpr const char* kScanId = "scan";
constexpr const char* kTextId = "overlay";
constexpr int kFontSize = 14;

pcl::PointCloud<pcl::PointXYZRGB>::Ptr toCloud(const ColouredPoints& pts) {
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZRGB>>();
  cloud->resize(pts.xyz.size());
  for (std::size_t i = 0; i < pts.xyz.size(); ++i) {
    pcl::PointXYZRGB& q = (*cloud)[i];
    q.x = pts.xyz[i].x();
    q.y = pts.xyz[i].y();
    q.z = pts.xyz[i].z();
    q.r = pts.rgb[i].r;
    q.g = pts.rgb[i].g;
    q.b = pts.rgb[i].b;
  }
  cloud->width = static_cast<std::uint32_t>(cloud->size());
  cloud->height = 1;
  return cloud;
}

/// A line actor (polyline or segments) whose geometry is replaced in place; lighting off, so its pixels
/// have exactly its colour.
struct LineActor {
  vtkSmartPointer<vtkPolyData> data = vtkSmartPointer<vtkPolyData>::New();
  vtkSmartPointer<vtkActor> actor = vtkSmartPointer<vtkActor>::New();
  LineActor(const Rgb& c, double width) {
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(data);
    actor->SetMapper(mapper);
    actor->GetProperty()->SetColor(c.r / 255.0, c.g / 255.0, c.b / 255.0);
    actor->GetProperty()->SetLineWidth(static_cast<float>(width));
    actor->GetProperty()->SetLighting(false);
    actor->GetProperty()->SetRenderLinesAsTubes(false);
  }
  /// `segments`: index pairs; empty: one polyline through all points.
  void set(const std::vector<livo::Vec3>& points, const std::vector<std::pair<int, int>>& segments) {
    auto pts = vtkSmartPointer<vtkPoints>::New();
    pts->SetNumberOfPoints(static_cast<vtkIdType>(points.size()));
    for (std::size_t i = 0; i < points.size(); ++i)
      pts->SetPoint(static_cast<vtkIdType>(i), points[i].x(), points[i].y(), points[i].z());
    auto lines = vtkSmartPointer<vtkCellArray>::New();
    if (segments.empty() && points.size() >= 2) {
      lines->InsertNextCell(static_cast<int>(points.size()));
      for (std::size_t i = 0; i < points.size(); ++i) lines->InsertCellPoint(static_cast<vtkIdType>(i));
    }
    for (const auto& [a, b] : segments) {
      lines->InsertNextCell(2);
      lines->InsertCellPoint(a);
      lines->InsertCellPoint(b);
    }
    data->SetPoints(pts);
    data->SetLines(lines);
    data->Modified();
    actor->SetVisibility(points.size() >= 2);
  }
};

}  // namespace

struct Renderer::Impl {
  RendererOptions opt;
  std::unique_ptr<pcl::visualization::PCLVisualizer> viz;
  vtkRenderer* ren = nullptr;
  LineActor trajectory{livo::viewer::kTrajectoryColour, 3.0};
  LineActor frustum{livo::viewer::kFrustumColour, 2.0};
  LineActor map_path{livo::viewer::kMapPathColour, 2.0};
  LineActor loop_edges{livo::viewer::kLoopEdgeColour, 2.0};
  vtkSmartPointer<vtkImageData> image = vtkSmartPointer<vtkImageData>::New();
  vtkSmartPointer<vtkImageMapper> image_mapper = vtkSmartPointer<vtkImageMapper>::New();
  vtkSmartPointer<vtkActor2D> image_actor = vtkSmartPointer<vtkActor2D>::New();
  bool have_map = false, have_scan = false, image_shown = false;
  bool closed = false;  ///< 'q', 'e' or the window closed
  vtkSmartPointer<vtkCallbackCommand> on_exit = vtkSmartPointer<vtkCallbackCommand>::New();
  std::mutex keys_mutex;
  std::vector<char> keys;

  void setCloud(const char* id, const ColouredPoints& pts, double size, bool& have) {
    const auto cloud = toCloud(pts);
    pcl::visualization::PointCloudColorHandlerRGBField<pcl::PointXYZRGB> colours(cloud);
    if (!have) {
      viz->addPointCloud<pcl::PointXYZRGB>(cloud, colours, id);
      have = true;
    } else {
      viz->updatePointCloud<pcl::PointXYZRGB>(cloud, colours, id);
    }
    viz->setPointCloudRenderingProperties(pcl::visualization::PCL_VISUALIZER_POINT_SIZE, size, id);
    const auto it = viz->getCloudActorMap()->find(id);
    if (it != viz->getCloudActorMap()->end() && it->second.actor) it->second.actor->GetProperty()->SetLighting(false);
  }
};

Renderer::Renderer(const RendererOptions& opt) : impl_(std::make_unique<Impl>()) {
  const std::string why = displayProblem();
  if (!why.empty()) throw std::runtime_error(why);
  Impl& m = *impl_;
  m.opt = opt;
  m.viz = std::make_unique<pcl::visualization::PCLVisualizer>(opt.title);
  vtkRenderWindow* win = m.viz->getRenderWindow();
  win->SetMultiSamples(0);  // exact colours at the edges of lines and points (the screenshot test reads them)
  m.viz->setSize(opt.width, opt.height);
  m.viz->setShowFPS(false);
  const Rgb bg = livo::viewer::kBackgroundColour;
  m.viz->setBackgroundColor(bg.r / 255.0, bg.g / 255.0, bg.b / 255.0);
  m.ren = m.viz->getRendererCollection()->GetFirstRenderer();
  m.trajectory = LineActor(livo::viewer::kTrajectoryColour, opt.line_width);
  m.ren->AddActor(m.trajectory.actor);
  m.ren->AddActor(m.frustum.actor);
  m.ren->AddActor(m.map_path.actor);
  m.ren->AddActor(m.loop_edges.actor);
  m.map_path.actor->SetVisibility(false);
  m.loop_edges.actor->SetVisibility(false);
  m.trajectory.actor->SetVisibility(false);
  m.frustum.actor->SetVisibility(false);
  m.viz->addText("", 10, 10, kFontSize, 0.95, 0.95, 0.95, kTextId);
  m.image_mapper->SetInputData(m.image);
  m.image_mapper->SetColorWindow(255.0);
  m.image_mapper->SetColorLevel(127.5);
  m.image_actor->SetMapper(m.image_mapper);
  // Quitting ('q', 'e', the window's close button) ends in the interactor's ExitEvent. PCL's observer of
  // it calls TerminateApp(), which crashes in Xlib when the interactor's loop is not running (we never
  // run it): ours comes first, notes the request and stops the event there.
  m.on_exit->SetClientData(&m.closed);
  m.on_exit->SetCallback([](vtkObject*, unsigned long, void* closed, void*) { *static_cast<bool*>(closed) = true; });
  m.on_exit->SetAbortFlagOnExecute(1);
  m.viz->getRenderWindow()->GetInteractor()->AddObserver(vtkCommand::ExitEvent, m.on_exit, 1.0f);
  m.viz->registerKeyboardCallback([this](const pcl::visualization::KeyboardEvent& e) {
    if (!e.keyDown()) return;
    std::lock_guard<std::mutex> lock(impl_->keys_mutex);
    impl_->keys.push_back(e.getKeyCode());
  });
}

// No PCLVisualizer::close(): in PCL 1.13 it calls TerminateApp() on an interactor loop that is not
// running (spinOnce() returned), which crashes in Xlib. The window goes with the visualiser.
Renderer::~Renderer() = default;

void Renderer::setMap(const ColouredPoints& pts) { impl_->setCloud(kMapId, pts, impl_->opt.point_size, impl_->have_map); }

void Renderer::setScan(const ColouredPoints& pts) {
  impl_->setCloud(kScanId, pts, impl_->opt.point_size + 1.0, impl_->have_scan);
}

void Renderer::setTrajectory(const std::vector<livo::viewer::PoseInput>& poses) {
  std::vector<livo::Vec3> pts;
  pts.reserve(poses.size());
  for (const auto& p : poses) pts.push_back(p.T_world_imu.translation());
  impl_->trajectory.set(pts, {});
}

void Renderer::setMapFrame(const std::vector<livo::Vec3>& path,
                           const std::vector<std::pair<livo::Vec3, livo::Vec3>>& loops) {
  impl_->map_path.set(path, {});
  std::vector<livo::Vec3> ends;
  std::vector<std::pair<int, int>> segments;
  for (const auto& [a, b] : loops) {
    segments.emplace_back(int(ends.size()), int(ends.size() + 1));
    ends.push_back(a);
    ends.push_back(b);
  }
  impl_->loop_edges.set(ends, segments);
}

void Renderer::setFrustum(const std::optional<std::array<livo::Vec3, 5>>& corners) {
  if (!corners) {
    impl_->frustum.actor->SetVisibility(false);
    return;
  }
  impl_->frustum.set(std::vector<livo::Vec3>(corners->begin(), corners->end()), livo::viewer::frustumSegments());
}

void Renderer::setText(const std::string& text) {
  // PCL places text by its lower left corner: keep the overlay's top line at the window's top.
  const int lines = 1 + static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  const int y = impl_->viz->getRenderWindow()->GetSize()[1] - 10 - lines * (kFontSize + 3);
  impl_->viz->updateText(text, 10, std::max(0, y), kFontSize, 0.95, 0.95, 0.95, kTextId);
}

void Renderer::setImage(const std::optional<livo::Image>& gray) {
  Impl& m = *impl_;
  if (!gray || gray->empty()) {
    if (m.image_shown) m.ren->RemoveActor2D(m.image_actor);
    m.image_shown = false;
    return;
  }
  m.image->SetDimensions(gray->width, gray->height, 1);
  m.image->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* dst = static_cast<unsigned char*>(m.image->GetScalarPointer());
  const int stride = gray->row_stride > 0 ? gray->row_stride : gray->width;
  for (int v = 0; v < gray->height; ++v)  // VTK's rows start at the bottom
    std::copy_n(gray->data.data() + std::size_t(gray->height - 1 - v) * stride, gray->width,
                dst + std::size_t(v) * gray->width);
  m.image->Modified();
  int* size = m.viz->getRenderWindow()->GetSize();
  m.image_actor->SetPosition(size[0] - gray->width - 10, size[1] - gray->height - 10);
  if (!m.image_shown) m.ren->AddActor2D(m.image_actor);
  m.image_shown = true;
}

void Renderer::setCamera(const livo::viewer::ViewCamera& c) {
  vtkCamera* cam = impl_->ren->GetActiveCamera();
  cam->SetPosition(c.position.x(), c.position.y(), c.position.z());
  cam->SetFocalPoint(c.focal.x(), c.focal.y(), c.focal.z());
  cam->SetViewUp(c.up.x(), c.up.y(), c.up.z());
  cam->SetParallelProjection(c.parallel);
  cam->SetParallelScale(c.parallel_scale);
  cam->SetViewAngle(c.view_angle_deg);
  impl_->ren->ResetCameraClippingRange();
}

bool Renderer::spinOnce(int ms) {
  if (impl_->closed || impl_->viz->wasStopped()) return false;
  impl_->ren->ResetCameraClippingRange();
  // Render, then handle the pending window events without waiting. Not PCLVisualizer::spinOnce():
  // with VTK 9.1 its ProcessEvents() waits in select() for the next X event or up to a second when no
  // timer is due, so a frame took 300-500 ms and scans were dropped.
  vtkRenderWindow* win = impl_->viz->getRenderWindow();
  win->Render();
  auto* display = static_cast<Display*>(win->GetGenericDisplayId());
  vtkRenderWindowInteractor* interactor = win->GetInteractor();
  for (int n = 0; display && interactor && XPending(display) > 0 && n < 1000; ++n) interactor->ProcessEvents();
  std::this_thread::sleep_for(std::chrono::milliseconds(ms));
  return !impl_->closed && !impl_->viz->wasStopped();
}

std::vector<char> Renderer::takeKeys() {
  std::lock_guard<std::mutex> lock(impl_->keys_mutex);
  std::vector<char> k;
  k.swap(impl_->keys);
  return k;
}

livo::viewer::ScreenshotInfo Renderer::saveScreenshot(const std::string& png_path) {
  Impl& m = *impl_;
  vtkRenderWindow* win = m.viz->getRenderWindow();
  m.ren->ResetCameraClippingRange();
  win->Render();
  auto grab = vtkSmartPointer<vtkWindowToImageFilter>::New();
  grab->SetInput(win);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  const auto parent = std::filesystem::path(png_path).parent_path();
  if (!parent.empty() && !std::filesystem::is_directory(parent))
    throw std::runtime_error(png_path + ": directory " + parent.string() + " does not exist");
  auto writer = vtkSmartPointer<vtkPNGWriter>::New();
  writer->SetFileName(png_path.c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  if (writer->GetErrorCode() != 0 || !std::filesystem::exists(png_path))
    throw std::runtime_error(png_path + ": cannot write the screenshot");
  livo::viewer::ScreenshotInfo info;
  int* size = win->GetSize();
  info.width = size[0];
  info.height = size[1];
  vtkMatrix4x4* w2n =
      m.ren->GetActiveCamera()->GetCompositeProjectionTransformMatrix(m.ren->GetTiledAspectRatio(), -1, 1);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) info.world_to_ndc(r, c) = w2n->GetElement(r, c);
  return info;
}

}  // namespace livo_viewer
