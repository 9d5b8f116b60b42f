// livo-report (scripts/livo-report, copied to build/bin): from a run directory with a known error
// against ground truth it writes the four plots and a summary whose ATE equals the oracle's; bad input
// gets a clear error; the map pictures of a synthetic room show what a top view must (the ceiling cut
// away, the table over the floor in the area ratio of the scene) from map.pcd written by PCL in each of
// its three encodings. Skipped when Debian's python3-matplotlib is missing.
// livo-test-deps: livo_eval livo_process opencv_core opencv_imgcodecs
// livo-test-bins: livo-report
#include "livo/eval/evaluate.hpp"
#include "livo/eval/tum.hpp"

#include "test_skip.hpp"

#include <opencv2/imgcodecs.hpp>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>

using namespace livo;
namespace fs = std::filesystem;

namespace {

const std::string kReport = std::string(LIVO_BINARY_DIR) + "/bin/livo-report";

bool haveMatplotlib() { return std::system("/usr/bin/python3 -c 'import matplotlib, numpy' >/dev/null 2>&1") == 0; }

std::string slurp(const std::string& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

int run(const std::string& cmd, std::string& out, const std::string& dir) {
  const int rc = std::system((cmd + " > " + dir + "/report.txt 2>&1").c_str());
  out = slurp(dir + "/report.txt");
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

}  // namespace

TEST(LivoReport, PlotsAndSummaryOfARunWithAKnownError) {
  if (!haveMatplotlib()) LIVO_SKIP() << "python3-matplotlib missing";
  const fs::path dir = fs::temp_directory_path() / ("livo_report_" + std::to_string(::getpid()));
  fs::create_directories(dir / "run");
  // Ground truth: a circle; estimate: rotated + shifted copy with noise (ATE after alignment = noise).
  Trajectory gt, est;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  Pose offset = Pose::Identity();
  offset.linear() = Eigen::AngleAxisd(0.7, Vec3::UnitZ()).toRotationMatrix();
  offset.translation() = Vec3(5, -2, 1);
  std::ofstream csv(dir / "run" / "frames.csv");
  csv << "t,lio_ms,vio_ms,total_ms,sigma_min,degenerate,visual_used,n_points,n_planes_matched,n_visual_points,"
         "map_bytes\n";
  for (int i = 0; i < 400; ++i) {
    const double t = 100.0 + 0.1 * i, a = 0.02 * i;
    Pose T = Pose::Identity();
    T.translation() = Vec3(10 * std::cos(a), 10 * std::sin(a), 0.1 * std::sin(3 * a));
    gt.push_back({t, T});
    Pose E = offset * T;
    E.translation() += Vec3(noise(rng), noise(rng), noise(rng));
    est.push_back({t, E});
    const bool deg = i % 50 < 5;
    csv << t << "," << 5 + i % 3 << "," << (deg ? 20 : 0) << "," << (deg ? 26 : 6) << "," << (deg ? 0.02 : 0.3) << ","
        << deg << "," << deg << ",1000,900,40," << 1000000 + 1000 * i << "\n";
  }
  csv.close();
  {
    std::ofstream g(dir / "gt.tum"), e(dir / "run" / "trajectory.tum");
    for (const auto& p : gt) writeTum(g, p);
    for (const auto& p : est) writeTum(e, p);
  }
  std::ofstream(dir / "run" / "stats.json")
      << R"({"frames": 400, "visual_mode": "adaptive", "map_mode": "hybrid", "peak_rss_mb": 50.0,
            "timing_ms": {"lio": {"mean": 6, "median": 6, "p95": 7, "max": 7},
                          "vio_per_visual_frame": {"mean": 20.5, "median": 20, "p95": 21, "max": 22}},
            "map": {"bytes": 1400000}})";
  const double oracle = evaluate(gt, est, EvalConfig{}).ate.translation_m.rmse;

  std::string out;
  ASSERT_EQ(run(kReport + " " + (dir / "run").string() + " --gt " + (dir / "gt.tum").string(), out, dir.string()), 0)
      << out;
  for (const char* png : {"trajectory.png", "timing.png", "sigma_min.png", "memory.png"}) {
    const fs::path p = dir / "run" / "report" / png;
    ASSERT_TRUE(fs::exists(p)) << png;
    EXPECT_GT(fs::file_size(p), 10000u) << png;
    EXPECT_EQ(slurp(p.string()).substr(1, 3), "PNG") << png;
  }
  const std::string md = slurp((dir / "run" / "report" / "README.md").string());
  std::ostringstream want;
  want.setf(std::ios::fixed);
  want.precision(2);
  want << "ATE RMSE (SE(3)-aligned) | " << oracle * 100 << " cm";
  EXPECT_NE(md.find(want.str()), std::string::npos) << md << "\nexpected " << want.str();
  EXPECT_NE(md.find("400 (40 with a visual update, 40 degenerate)"), std::string::npos) << md;
  EXPECT_NE(md.find("![memory](memory.png)"), std::string::npos) << md;
  EXPECT_NE(md.find("| vio ms per visual frame (mean / median / p95 / max) | 20.50 / 20.00 / 21.00 / 22.00 |"),
            std::string::npos)
      << md;

  // Bad input: a clear error naming the problem, exit code 2.
  EXPECT_EQ(run(kReport + " " + dir.string(), out, dir.string()), 2);
  EXPECT_NE(out.find("trajectory.tum missing"), std::string::npos) << out;
  std::ofstream(dir / "bad.tum") << "1 2 3\n";
  EXPECT_EQ(run(kReport + " " + (dir / "run").string() + " --gt " + (dir / "bad.tum").string(), out, dir.string()), 2);
  EXPECT_NE(out.find("bad.tum:1: expected 8 columns"), std::string::npos) << out;
  fs::remove_all(dir);
}

namespace {

/// Pixels of `img` (BGR) within 3 of the colour (r, g, b) in every channel.
std::size_t countColour(const cv::Mat& img, int r, int g, int b) {
  std::size_t n = 0;
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
      n += std::abs(p[2] - r) <= 3 && std::abs(p[1] - g) <= 3 && std::abs(p[0] - b) <= 3;
    }
  return n;
}

}  // namespace

TEST(LivoReport, MapPicturesShowTheRoomFromAboveWithoutItsCeiling) {
  if (!haveMatplotlib()) LIVO_SKIP() << "python3-matplotlib missing";
  const fs::path dir = fs::temp_directory_path() / ("livo_report_map_" + std::to_string(::getpid()));
  fs::create_directories(dir / "run");
  // A 4 m x 3 m room sampled every 5 cm: the floor (z = 0), a 1 m x 1 m table top at 0.7 m, a ceiling at
  // 2.5 m, each in a colour of its own ("camera" colours); a circle of poses at 1 m height.
  const double step = 0.05;
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  const auto add = [&](double x, double y, double z, int r, int g, int b) {
    pcl::PointXYZRGB p;
    p.x = float(x);
    p.y = float(y);
    p.z = float(z);
    p.r = std::uint8_t(r);
    p.g = std::uint8_t(g);
    p.b = std::uint8_t(b);
    cloud.push_back(p);
  };
  for (double x = step / 2; x < 4.0; x += step)
    for (double y = step / 2; y < 3.0; y += step) {
      add(x, y, 0.0, 180, 60, 20);
      add(x, y, 2.5, 60, 20, 180);
      if (x > 2.8 && x < 3.8 && y > 0.2 && y < 1.2) add(x, y, 0.7, 20, 180, 60);
    }
  cloud.width = std::uint32_t(cloud.size());
  cloud.height = 1;
  {
    std::ofstream tum(dir / "run" / "trajectory.tum"), csv(dir / "run" / "frames.csv");
    csv << "t,lio_ms,vio_ms,total_ms,sigma_min,degenerate,visual_used,n_points,n_planes_matched,n_visual_points,map_bytes,"
           "n_longterm_points\n";
    for (int i = 0; i < 100; ++i) {
      const double a = 2 * M_PI * i / 100, t = 10.0 + 0.1 * i;
      Pose T = Pose::Identity();
      T.translation() = Vec3(1.6 + 0.6 * std::cos(a), 1.6 + 0.6 * std::sin(a), 1.0);
      writeTum(tum, {t, T});
      csv << t << ",5,1,6,0.3,0,1,1000,900,40,1000000," << (i >= 60 ? 10 : 0) << "\n";  // a revisit from 16 s
    }
  }
  std::ofstream(dir / "run" / "stats.json") << R"({"frames": 100, "visual_frames": 100, "map": {"bytes": 1000000}})";

  std::vector<std::size_t> floors;
  for (const std::string encoding : {"binary", "binary_compressed", "ascii"}) {
    const std::string pcd = (dir / "run" / "map.pcd").string();
    const int rc = encoding == "binary"              ? pcl::io::savePCDFileBinary(pcd, cloud)
                   : encoding == "binary_compressed" ? pcl::io::savePCDFileBinaryCompressed(pcd, cloud)
                                                     : pcl::io::savePCDFileASCII(pcd, cloud);
    ASSERT_EQ(rc, 0) << encoding;
    std::string out;
    ASSERT_EQ(run(kReport + " " + (dir / "run").string(), out, dir.string()), 0) << encoding << "\n" << out;
    for (const char* png : {"map_top.png", "map_oblique.png"})
      ASSERT_TRUE(fs::exists(dir / "run" / "report" / png)) << encoding << " " << png;
    const std::string md = slurp((dir / "run" / "report" / "README.md").string());
    EXPECT_NE(md.find("![map, top](map_top.png)"), std::string::npos) << md;
    EXPECT_NE(md.find("![map, oblique](map_oblique.png)"), std::string::npos) << md;
    // The long-term map's points on the timeline and their share: 40 frames x 10 of 100 x 40 used.
    EXPECT_TRUE(fs::exists(dir / "run" / "report" / "visual_points.png")) << encoding;
    EXPECT_NE(md.find("| visual points through the long-term map | 10.0 % of 4000; on 40 visual frames |"), std::string::npos)
        << md;
    // The camera-coloured top view (exact colours: no shading from above): no ceiling (cut at the highest
    // pose + 1 m), the table's top hides the floor below it: table / (table + floor) is the table's share
    // of the room, 1 / 12, up to the pixels at the edges and under the trajectory's line.
    const cv::Mat top = cv::imread((dir / "run" / "report" / "map_top.png").string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(top.empty());
    const std::size_t floor = countColour(top, 180, 60, 20), table = countColour(top, 20, 180, 60),
                      ceiling = countColour(top, 60, 20, 180);
    std::cout << encoding << ": top view pixels: floor " << floor << ", table " << table << ", ceiling " << ceiling << "\n";
    EXPECT_EQ(ceiling, 0u) << encoding;
    EXPECT_GT(floor, 50000u) << encoding;
    EXPECT_NEAR(double(table) / double(table + floor), 1.0 / 12.0, 0.015) << encoding;
    floors.push_back(floor);
  }
  EXPECT_EQ(floors[0], floors[1]) << "binary and binary_compressed give the same picture";
  EXPECT_EQ(floors[0], floors[2]) << "binary and ascii give the same picture";

  // A damaged map.pcd: a clear error naming the file, exit code 2.
  std::ofstream(dir / "run" / "map.pcd") << "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1000\nHEIGHT 1\nPOINTS 1000\nDATA binary\n";
  std::string out;
  EXPECT_EQ(run(kReport + " " + (dir / "run").string(), out, dir.string()), 2);
  EXPECT_NE(out.find("map.pcd: truncated"), std::string::npos) << out;
  fs::remove_all(dir);
}

// The health timeline: a run whose frames.csv states are 10 frames initialising, 50 ok, 10 with the
// LiDAR failed and an image used, 20 on the IMU alone and 10 ok again (0.1 s each): every state is drawn
// in its colour, each over a length of the time axis proportional to its frames, and the summary
// quotes stats.json's health figures.
TEST(LivoReport, HealthTimelineDrawsEveryStateInProportion) {
  if (!haveMatplotlib()) LIVO_SKIP() << "python3-matplotlib missing";
  const fs::path dir = fs::temp_directory_path() / ("livo_report_health_" + std::to_string(::getpid()));
  fs::create_directories(dir / "run");
  std::ofstream csv(dir / "run" / "frames.csv");
  csv << "t,lio_ms,vio_ms,total_ms,sigma_min,degenerate,visual_used,n_points,n_planes_matched,n_visual_points,"
         "map_bytes,n_longterm_points,time_offset_s,time_offset_sigma_s,state,reason\n";
  std::ofstream tum(dir / "run" / "trajectory.tum");
  for (int i = 0; i < 100; ++i) {
    const double t = 50.0 + 0.1 * i;
    const char* state = i < 10 ? "initialising" : i < 60 ? "ok" : i < 70 ? "degraded" : i < 90 ? "lost" : "ok";
    const bool visual = i >= 60 && i < 70;
    csv << t << ",5,0,6,0.3,0," << visual << ",1000,900,0,0,0,nan,nan," << state << ","
        << (i >= 60 && i < 90 ? "LiDAR correction chi2 85 above 22.5" : "") << "\n";
    if (i >= 10) tum << t << " " << 0.1 * i << " 0 0 0 0 0 1\n";
  }
  csv.close();
  tum.close();
  std::ofstream(dir / "run" / "stats.json")
      << R"({"frames": 100, "visual_mode": "adaptive", "map_mode": "hybrid",
            "health": {"first_pose_delay_s": 1, "initialising_s": 1, "lidar_failed_s": 3, "imu_only_s": 2,
                       "degenerate_s": 0, "degraded_s": 1, "lost_s": 2, "lost_spans": 1,
                       "longest_pose_gap_s": 0.1}})";
  std::string out;
  ASSERT_EQ(run(kReport + " " + (dir / "run").string(), out, dir.string()), 0) << out;
  const std::string md = slurp((dir / "run" / "report" / "README.md").string());
  EXPECT_NE(md.find("| health | first pose 1.00 s after the first frame; initialising 1.0 s, LiDAR failed 3.0 s, "
                    "IMU only 2.0 s, degenerate 0.0 s, degraded 1.0 s, lost 2.0 s (1 spans); longest pose gap 0.10 s |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("![health](health.png)"), std::string::npos) << md;
  const cv::Mat img = cv::imread((dir / "run" / "report" / "health.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  // The bars' colours (scripts/livo-report STATES); the legend adds the same small swatch to each.
  const double init = double(countColour(img, 0x9e, 0x9e, 0x9e)), ok = double(countColour(img, 0x55, 0xa8, 0x68));
  const double failed = double(countColour(img, 0xdd, 0x84, 0x52)), imu = double(countColour(img, 0xc4, 0x4e, 0x52));
  ASSERT_GT(init, 0.0);
  ASSERT_GT(failed, 0.0);
  std::cout << "health.png pixels: initialising " << init << ", ok " << ok << ", degraded " << failed
            << ", lost " << imu << "\n";
  // Each count is a bar's length times its height plus the legend's swatch (the same for every state):
  // differences cancel the swatch.
  EXPECT_NEAR((ok - init) / (imu - init), 5.0, 0.5) << "60 frames ok, 20 lost, 10 initialising";
  EXPECT_NEAR(failed / init, 1.0, 0.1) << "10 frames each";
  fs::remove_all(dir);
}
