// Shared helpers of the libs/eval tests (tests/test_eval_*.cpp): a per-process temporary folder, text and
// TUM files written into it, the message of a thrown exception, a synthetic ground-truth trajectory and
// its perturbation by a known Sim(3) and Gaussian noise of known sigma.
#pragma once

#include "livo/eval/evaluate.hpp"

#include <unistd.h>

#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace livo::test {

namespace fs = std::filesystem;

// A fresh directory per test process for temporary files, removed at exit.
struct TempDir {
  fs::path path = fs::temp_directory_path() / ("livo_test_eval_" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};
inline fs::path tempDir() {
  static const TempDir dir;
  return dir.path;
}

inline std::string writeText(const std::string& name, const std::string& text) {
  const fs::path p = tempDir() / name;
  std::ofstream(p) << text;
  return p.string();
}

inline std::string writeTrajectory(const std::string& name, const Trajectory& traj) {
  const fs::path p = tempDir() / name;
  TumWriter writer(p.string());
  for (const StampedPose& s : traj) writer.write(s);
  return p.string();
}

// Message of the std::exception thrown by f ("" when nothing is thrown).
template <class F>
inline std::string errorOf(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// 120 s at 20 Hz: a Lissajous loop with height changes; yaw follows the direction of travel, roll
// and pitch oscillate.
inline Trajectory syntheticTrajectory() {
  Trajectory traj;
  for (int k = 0; k < 2400; ++k) {
    const double t = 1000.0 + 0.05 * k;
    const double w = 2 * M_PI / 60.0;
    const Vec3 p(6 * std::cos(w * t), 4 * std::sin(2 * w * t), 1.5 + 0.5 * std::sin(0.3 * t));
    const Vec3 v(-6 * w * std::sin(w * t), 8 * w * std::cos(2 * w * t), 0.15 * std::cos(0.3 * t));
    StampedPose s;
    s.t = t;
    s.T_world_body.linear() = expSO3(Vec3(0, 0, std::atan2(v.y(), v.x()))) *
                              expSO3(Vec3(0, 0.1 * std::sin(0.5 * t), 0)) *
                              expSO3(Vec3(0.2 * std::sin(0.7 * t), 0, 0));
    s.T_world_body.translation() = p;
    traj.push_back(s);
  }
  return traj;
}

struct Perturbation {
  Sim3 T_est_gt;              // applied to the (noisy) ground truth to make the estimate
  double sigma_pos_m = 0;     // per-axis position noise, added in the ground-truth frame
  double sigma_rot_rad = 0;   // per-axis rotation noise, right-multiplied on the body orientation
  unsigned seed = 1;
};

inline Trajectory perturb(const Trajectory& gt, const Perturbation& p) {
  std::mt19937 rng(p.seed);
  std::normal_distribution<double> n(0.0, 1.0);
  Trajectory est = gt;
  for (StampedPose& s : est) {
    Pose noisy = s.T_world_body;
    noisy.translation() += p.sigma_pos_m * Vec3(n(rng), n(rng), n(rng));
    noisy.linear() = noisy.linear() * expSO3(p.sigma_rot_rad * Vec3(n(rng), n(rng), n(rng)));
    s.T_world_body = p.T_est_gt.apply(noisy);
  }
  return est;
}

inline Sim3 knownTransform(double scale) {
  Sim3 T;
  T.R = expSO3(Vec3(0.3, -0.8, 2.1));
  T.t = Vec3(12.5, -3.0, 0.7);
  T.s = scale;
  return T;
}

}  // namespace livo::test
