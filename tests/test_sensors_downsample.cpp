// libs/sensors: voxel downsampling against a brute-force grouping.
#include "sensors_test_util.hpp"

#include "livo/sensors/downsample.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <vector>

using namespace livo;
using namespace livo::test;

// ------------------------------------------------------------------ voxel downsampling

namespace {

struct BruteVoxel {
  std::size_t first;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double t = 0.0;
  int n = 0;
};

std::vector<BruteVoxel> bruteGroups(const std::vector<LidarPoint>& pts, double leaf) {
  std::map<std::tuple<long, long, long>, BruteVoxel> groups;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3d p = pts[i].p_lidar.cast<double>();
    if (!p.allFinite()) continue;
    const auto key = std::make_tuple(static_cast<long>(std::floor(p.x() / leaf)),
                                     static_cast<long>(std::floor(p.y() / leaf)),
                                     static_cast<long>(std::floor(p.z() / leaf)));
    auto it = groups.find(key);
    if (it == groups.end()) it = groups.emplace(key, BruteVoxel{i}).first;
    it->second.sum += p;
    it->second.t += pts[i].time_offset_s;
    ++it->second.n;
  }
  std::vector<BruteVoxel> out;
  for (const auto& kv : groups) out.push_back(kv.second);
  std::sort(out.begin(), out.end(), [](const BruteVoxel& a, const BruteVoxel& b) { return a.first < b.first; });
  return out;
}

}  // namespace

TEST(VoxelDownsample, MatchesBruteForceGrouping) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  std::vector<LidarPoint> pts;
  for (int i = 0; i < 20000; ++i) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(static_cast<float>(u(rng)), static_cast<float>(u(rng) * 0.1),
                                static_cast<float>(u(rng) * 0.05));
    p.time_offset_s = static_cast<float>((u(rng) + 20.0) / 400.0);
    p.ring = static_cast<std::int16_t>(i % 32);
    pts.push_back(p);
  }
  // Points exactly on voxel faces, at the origin and at negative faces, and a NaN.
  for (float v : {0.0f, -0.5f, 0.5f, -1.0f, -0.25f}) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(v, -v, v);
    pts.push_back(p);
  }
  pts.push_back(LidarPoint{});
  pts.back().p_lidar.x() = kNaN;

  for (float leaf : {0.5f, 0.25f, 0.1f, 1.0f}) {
    SCOPED_TRACE("leaf " + std::to_string(leaf));
    const auto out = voxelDownsample(pts, leaf);
    const auto ref = bruteGroups(pts, static_cast<double>(leaf));
    ASSERT_EQ(out.size(), ref.size());
    for (std::size_t v = 0; v < out.size(); ++v) {
      const Eigen::Vector3d c = ref[v].sum / ref[v].n;
      EXPECT_LT((out[v].p_lidar.cast<double>() - c).norm(), 1e-5);
      EXPECT_NEAR(out[v].time_offset_s, ref[v].t / ref[v].n, 1e-7);
      EXPECT_EQ(out[v].ring, pts[ref[v].first].ring);
    }
    // The Vector3d variant groups identically.
    std::vector<Eigen::Vector3d> pd;
    for (const LidarPoint& p : pts) pd.push_back(p.p_lidar.cast<double>());
    const auto outd = voxelDownsample(pd, static_cast<double>(leaf));
    ASSERT_EQ(outd.size(), ref.size());
    for (std::size_t v = 0; v < outd.size(); ++v) EXPECT_LT((outd[v] - ref[v].sum / ref[v].n).norm(), 1e-9);
  }
  EXPECT_EQ(voxelDownsample(pts, 0.f).size(), pts.size());
}
