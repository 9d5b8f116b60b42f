// livo-viewer's command line and its run-directory replay: usage errors exit 2, a missing display, a
// missing run directory or a bad map.pcd exit 1 with a message naming the cause (the run directory is
// checked before the display), --print-config prints the channels and the camera it reads and loads
// back; under Xvfb, `--run DIR --speed 0 --view top --screenshot-at` draws a known trajectory exactly
// where its sidecar's camera matrix projects it (no estimator involved: an exact oracle).
// livo-test-bins: livo-viewer
// livo-test-deps: livo_eval opencv_core opencv_imgcodecs
// livo-test-xserver: starts Xvfb (its tests run one at a time with the others that do)
#include "viewer_test_util.hpp"
#include "livo/eval/tum.hpp"
#include "livo/viewer/colour.hpp"

#include "process_test_display.hpp"
#include "process_test_files.hpp"
#include "test_skip.hpp"

#include <opencv2/imgcodecs.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace livo;
using namespace livo::test;

namespace {

const std::string kViewer = kBin + "/livo-viewer";

/// Runs `cmd` (a shell line), output into `out`; returns the exit code.
int run(const std::string& cmd, std::string& out, const std::string& dir) {
  const int rc = std::system((cmd + " > " + dir + "/out.txt 2>&1").c_str());
  out = readFile(dir + "/out.txt");
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// A run directory: a circle of radius 2 m around (1, -1) at 1 m height, and a floor of points.
void writeRun(const std::string& dir) {
  std::filesystem::create_directories(dir);
  std::ofstream tum(dir + "/trajectory.tum");
  for (int i = 0; i <= 200; ++i) {
    const double a = 2 * M_PI * i / 200;
    Pose T = Pose::Identity();
    T.linear() = Eigen::AngleAxisd(a + M_PI / 2, Vec3::UnitZ()).toRotationMatrix();
    T.translation() = Vec3(1 + 2 * std::cos(a), -1 + 2 * std::sin(a), 1.0);
    writeTum(tum, {100.0 + 0.1 * i, T});
  }
  std::ofstream pcd(dir + "/map.pcd");
  std::ostringstream pts;
  int n = 0;
  for (int i = 0; i <= 60; ++i)
    for (int j = 0; j <= 60; ++j, ++n) pts << -2 + 0.1 * i << " " << -4 + 0.1 * j << " 0 " << 0x808080 << "\n";
  pcd << "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH " << n
      << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << n << "\nDATA ascii\n"
      << pts.str();
}

using livo_test::jsonNumbers;

}  // namespace

TEST(ViewerCli, UsageDisplayAndRunDirectoryErrors) {
  const std::string dir = tempDir("viewer_cli");
  std::string out;
  EXPECT_EQ(run(kViewer + " --view sideways", out, dir), 2);
  EXPECT_NE(out.find("--view: expected one of follow|top|free, got 'sideways'"), std::string::npos) << out;
  EXPECT_EQ(run(kViewer + " --screenshot-at 3", out, dir), 2);
  EXPECT_NE(out.find("--screenshot-at: missing value (FILE) after '3'"), std::string::npos) << out;
  EXPECT_EQ(run(kViewer + " --config " + dir + "/none.yaml", out, dir), 2);
  EXPECT_NE(out.find("none.yaml"), std::string::npos) << out;
  EXPECT_EQ(run("env -u DISPLAY " + kViewer, out, dir), 1);
  EXPECT_NE(out.find("livo-viewer: no X display: DISPLAY is not set"), std::string::npos) << out;
  // The run directory is checked first, so its errors show without a display too.
  EXPECT_EQ(run("env -u DISPLAY " + kViewer + " --run " + dir + "/missing", out, dir), 1);
  EXPECT_NE(out.find(dir + "/missing: no such directory"), std::string::npos) << out;
  writeRun(dir + "/run");
  std::ofstream(dir + "/run/map.pcd") << "garbage\n";
  EXPECT_EQ(run("env -u DISPLAY " + kViewer + " --run " + dir + "/run", out, dir), 1);
  EXPECT_NE(out.find(dir + "/run/map.pcd: not a PCD file (line 1: unknown header line 'garbage')"), std::string::npos)
      << out;
  std::ofstream(dir + "/run/trajectory.tum") << "1 2 3\n";
  EXPECT_EQ(run("env -u DISPLAY " + kViewer + " --run " + dir + "/run", out, dir), 1);
  EXPECT_NE(out.find("trajectory.tum:1"), std::string::npos) << out;
}

TEST(ViewerCli, PrintConfigNamesItsSectionsAndLoadsBack) {
  const std::string dir = tempDir("viewer_print_config");
  std::ofstream(dir + "/rig.yaml") << "channels: {odometry: MY_ODOM}\n"
                                      "camera: {width: 640, height: 480, fx: 400, fy: 400, cx: 320, cy: 240,\n"
                                      "         T_imu_camera: [0, 0, 0, -0.5, 0.5, -0.5, 0.5]}\n"
                                      "lio: {whatever: 1}\n";  // another binary's section: not checked here
  std::string out;
  ASSERT_EQ(run(kViewer + " --config " + dir + "/rig.yaml --print-config", out, dir), 0) << out;
  EXPECT_NE(out.find("odometry: MY_ODOM"), std::string::npos) << out;
  EXPECT_NE(out.find("fx: 400"), std::string::npos) << out;
  std::ofstream(dir + "/effective.yaml") << out;
  std::string again;
  ASSERT_EQ(run(kViewer + " --config " + dir + "/effective.yaml --print-config", again, dir), 0) << again;
  EXPECT_EQ(again, out);
  std::ofstream(dir + "/typo.yaml") << "channels: {odometri: X}\n";
  EXPECT_EQ(run(kViewer + " --config " + dir + "/typo.yaml --print-config", out, dir), 2);
  EXPECT_NE(out.find("channels.odometri: unknown key"), std::string::npos) << out;
}

TEST(ViewerCli, RunDirectoryDrawsTheTrajectoryWhereTheCameraMatrixPutsIt) {
  const std::string dir = tempDir("viewer_run_shot");
  XServer x(nullptr, dir);
  if (!x.ok) LIVO_SKIP() << x.why;
  writeRun(dir + "/run");
  const std::string png = dir + "/shot.png";
  std::string out;
  ASSERT_EQ(run("env DISPLAY=" + x.display + " " + kViewer + " --run " + dir + "/run --speed 0 --view top " +
                    "--screenshot-at 1000 " + png,
                out, dir),
            0)
      << out << x.report();
  EXPECT_NE(out.find("201 poses; map.pcd: 3721 points (x y z rgb)"), std::string::npos) << out;
  const cv::Mat img = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << out;
  const std::string json = readFile(dir + "/shot.json");
  const std::vector<double> m = jsonNumbers(json, "world_to_ndc");
  ASSERT_EQ(m.size(), 16u) << json;
  Eigen::Matrix4d P;
  for (int i = 0; i < 16; ++i) P(i / 4, i % 4) = m[i];
  const viewer::Rgb traj = viewer::kTrajectoryColour;
  // Every trajectory pixel at the circle's projected radius from its projected centre (a parallel top
  // view: the circle stays a circle), and pixels all around it.
  const auto project = [&](const Vec3& p) {
    const Eigen::Vector4d ndc = P * p.homogeneous();
    return Eigen::Vector2d((ndc.x() / ndc.w() + 1) / 2 * img.cols, (1 - ndc.y() / ndc.w()) / 2 * img.rows);
  };
  const Eigen::Vector2d centre = project(Vec3(1, -1, 1));
  const double radius = (project(Vec3(3, -1, 1)) - centre).norm();
  double worst = 0;
  std::size_t n = 0;
  std::vector<bool> sectors(36, false);
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) {
      const cv::Vec3b p = img.at<cv::Vec3b>(r, c);
      if (std::abs(p[2] - traj.r) + std::abs(p[1] - traj.g) + std::abs(p[0] - traj.b) > 6) continue;
      const Eigen::Vector2d q(c + 0.5, r + 0.5);
      worst = std::max(worst, std::abs((q - centre).norm() - radius));
      const double a = std::atan2(q.y() - centre.y(), q.x() - centre.x());
      sectors[static_cast<std::size_t>((a + M_PI) / (2 * M_PI) * 35.999)] = true;
      ++n;
    }
  std::size_t covered = 0;
  for (const bool s : sectors) covered += s;
  std::cout << n << " trajectory pixels, radius " << radius << " px, worst " << worst << " px off the circle, "
            << covered << " of 36 sectors\n";
  EXPECT_GT(n, 500u);
  EXPECT_LE(worst, 2.5);  // the 3 px line and the 200-gon's chords
  EXPECT_GE(covered, 34u) << "the frustum may hide a little of it";
}
