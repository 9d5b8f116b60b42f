// libs/sensors camera models on a real calibration: the EuRoC V1_01 cam0 (and cam1 if present) radtan calibration
// (../shared/data/euroc_v1_01_micro) undistorts its images consistently with OpenCV
// (cv::initUndistortRectifyMap + cv::remap), and the fisheye undistortion tables agree with
// cv::fisheye::initUndistortRectifyMap (no real fisheye data is shipped: the Hilti-like model is synthetic).
// livo-test-deps: livo_datasets opencv_core opencv_imgproc opencv_calib3d opencv_imgcodecs
#include "livo/datasets/euroc.hpp"
#include "livo/sensors/camera_model.hpp"
#include "livo/sensors/camera_model_undistort.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>

using namespace livo;
namespace fs = std::filesystem;

namespace {

const fs::path kEuroc = fs::path(LIVO_SHARED_DATA) / "euroc_v1_01_micro" / "mav0";

cv::Matx33d cvK(const CameraModel& c) { return {c.fx(), 0, c.cx(), 0, c.fy(), c.cy(), 0, 0, 1}; }
cv::Vec4d cvD(const CameraModel& c) { return {c.distortion()[0], c.distortion()[1], c.distortion()[2], c.distortion()[3]}; }

struct MapComparison {
  double max_px = 0;        // max |our table - OpenCV's table| over all entries
  double max_ray_px = 0;    // max angle between unproject(table entry) and the ideal ray, x fx
  int compared = 0;
};

// Our tables against OpenCV's, and unproject() of every table entry against the ideal pixel's ray.
MapComparison compareMaps(const CameraModel& cam, const IdealPinhole& ideal, const UndistortionMap& ours,
                          const cv::Mat& cv_x, const cv::Mat& cv_y) {
  MapComparison c;
  for (int v = 0; v < ideal.height; ++v) {
    for (int u = 0; u < ideal.width; ++u) {
      const size_t i = static_cast<size_t>(v) * ideal.width + u;
      const Eigen::Vector2d mine(ours.map_x[i], ours.map_y[i]);
      c.max_px = std::max(c.max_px, (mine - Eigen::Vector2d(cv_x.at<float>(v, u), cv_y.at<float>(v, u))).norm());
      ++c.compared;
      Eigen::Vector3d b;
      if (!cam.inImage(mine, 0)) continue;  // rays that leave the real image
      EXPECT_TRUE(cam.unproject(mine, b));
      const Eigen::Vector3d ray = Eigen::Vector3d((u - ideal.cx) / ideal.fx, (v - ideal.cy) / ideal.fy, 1).normalized();
      c.max_ray_px = std::max(c.max_ray_px, std::atan2(b.cross(ray).norm(), b.dot(ray)) * cam.fx());
    }
  }
  return c;
}

}  // namespace

TEST(EurocCamera, UndistortionMatchesOpenCv) {
  if (!fs::exists(kEuroc / "cam0" / "sensor.yaml")) LIVO_SKIP() << "no EuRoC data at " << kEuroc;
  for (const char* cam_name : {"cam0", "cam1"}) {
    const fs::path dir = kEuroc / cam_name;
    if (!fs::exists(dir / "sensor.yaml")) continue;
    const EurocCameraCalibration calib = readEurocCameraYaml((dir / "sensor.yaml").string());
    CameraConfig cfg;
    cfg.model = calib.model, cfg.width = calib.width, cfg.height = calib.height;
    cfg.fx = calib.fx, cfg.fy = calib.fy, cfg.cx = calib.cx, cfg.cy = calib.cy;
    cfg.distortion = calib.distortion;
    const auto cam = CameraModel::create(cfg);
    ASSERT_EQ(cam->width(), 752);
    ASSERT_EQ(cam->height(), 480);

    // Tables: ours (ideal pinhole with the same K) and OpenCV's with R = I, newK = K.
    const IdealPinhole ideal = IdealPinhole::sameAs(*cam);
    const UndistortionMap ours = buildUndistortionMap(*cam, ideal);
    EXPECT_EQ(ours.invalid, 0);
    cv::Mat cv_x, cv_y;
    cv::initUndistortRectifyMap(cvK(*cam), cvD(*cam), cv::Mat(), cvK(*cam), cv::Size(ideal.width, ideal.height),
                                CV_32FC1, cv_x, cv_y);
    const MapComparison cmp = compareMaps(*cam, ideal, ours, cv_x, cv_y);
    EXPECT_LT(cmp.max_px, 0.01);
    EXPECT_LT(cmp.max_ray_px, 1e-3);  // float tables: ~1e-4 px rounding

    // A real image remapped through both tables.
    std::vector<fs::path> images;
    for (const auto& e : fs::directory_iterator(dir / "data"))
      if (e.path().extension() == ".png") images.push_back(e.path());
    ASSERT_FALSE(images.empty());
    std::sort(images.begin(), images.end());
    const cv::Mat img = cv::imread(images[images.size() / 2].string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(img.empty()) << images[images.size() / 2];
    const cv::Mat our_x(ideal.height, ideal.width, CV_32F, const_cast<float*>(ours.map_x.data()));
    const cv::Mat our_y(ideal.height, ideal.width, CV_32F, const_cast<float*>(ours.map_y.data()));
    cv::Mat und_ours, und_cv, diff;
    cv::remap(img, und_ours, our_x, our_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
    cv::remap(img, und_cv, cv_x, cv_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
    cv::absdiff(und_ours, und_cv, diff);
    double max_diff = 0;
    cv::minMaxLoc(diff, nullptr, &max_diff);
    const double mean_diff = cv::mean(diff)[0];
    std::cout << "[ figures ] EuRoC " << cam_name << " (" << images[images.size() / 2].filename().string()
              << "): tables vs initUndistortRectifyMap max " << cmp.max_px << " px over " << cmp.compared
              << " entries; unproject(table) vs ideal ray max " << cmp.max_ray_px
              << " px; remapped images mean |diff| " << mean_diff << " gray, max " << max_diff << "\n";
    EXPECT_LT(mean_diff, 0.05);
    EXPECT_LE(max_diff, 2.0);
  }
}

// FAST-LIVO2's Equidistant camera cannot undistort images (§8 #246); ours builds the same tables as OpenCV.
TEST(EurocCamera, FisheyeUndistortionTablesMatchOpenCv) {
  const Equidistant cam(720, 540, 351.3, 351.6, 365.1, 267.9, {-0.01, 0.02, -0.01, 0.003});
  IdealPinhole ideal = IdealPinhole::sameAs(cam);
  ideal.fx = ideal.fy = 200.0;  // a wider ideal view so the corners reach ~64 deg
  ideal.cx = 359.5, ideal.cy = 269.5;
  const UndistortionMap ours = buildUndistortionMap(cam, ideal);
  EXPECT_EQ(ours.invalid, 0);
  cv::Mat cv_x, cv_y;
  const cv::Matx33d newK(ideal.fx, 0, ideal.cx, 0, ideal.fy, ideal.cy, 0, 0, 1);
  cv::fisheye::initUndistortRectifyMap(cvK(cam), cvD(cam), cv::Matx33d::eye(), newK,
                                       cv::Size(ideal.width, ideal.height), CV_32FC1, cv_x, cv_y);
  const MapComparison cmp = compareMaps(cam, ideal, ours, cv_x, cv_y);
  std::cout << "[ figures ] fisheye tables vs cv::fisheye::initUndistortRectifyMap max " << cmp.max_px
            << " px; unproject(table) vs ideal ray max " << cmp.max_ray_px << " px\n";
  EXPECT_LT(cmp.max_px, 0.01);
  EXPECT_LT(cmp.max_ray_px, 1e-3);
}
