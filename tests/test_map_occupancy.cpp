// libs/map: the correlative translation search (occupancy_search.hpp) against a known shift and
// against brute force over every candidate of the finest grid; a geometry that cannot tell
// translations apart keeps the prediction along that direction; empty inputs and bad arguments.
#include "livo/map/occupancy_search.hpp"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <vector>

using namespace livo;

namespace {

// Points sampled at random on a room's floor and two walls, plus a few boxes (distinct surfaces in
// every direction). Each call samples other spots: the map and the query never share a point.
std::vector<Vec3> sampleRoom(std::mt19937& rng, int n, bool corridor, double half_length = 10.0) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> pts;
  for (int i = 0; i < n; ++i) {
    const double a = u(rng), b = u(rng);
    switch (corridor ? i % 3 : i % 6) {
      case 0: pts.emplace_back(half_length * (2 * a - 1), -1.5 + 3 * b, 0.0); break;  // floor
      case 1: pts.emplace_back(half_length * (2 * a - 1), -1.5, 2.5 * b); break;       // wall y = -1.5
      case 2: pts.emplace_back(half_length * (2 * a - 1), 1.5, 2.5 * b); break;        // wall y = +1.5
      case 3: pts.emplace_back(4.0, -1.5 + 3 * a, 2.5 * b); break;        // end wall x = 4
      case 4: pts.emplace_back(-2.0 + 0.6 * a, -0.6, 1.2 * b); break;     // a box face
      default: pts.emplace_back(1.0, 0.2 + 0.8 * a, 1.5 * b); break;      // another one
    }
  }
  return pts;
}

OccupancyPyramid pyramidOf(const std::vector<Vec3>& pts) {
  OccupancyPyramid o(0.15, 5);
  for (const auto& p : pts) o.insert(p);
  return o;
}

}  // namespace

TEST(OccupancySearch, FindsAKnownShiftFromOtherSamplesOfTheSameSurfaces) {
  std::mt19937 rng(3);
  const OccupancyPyramid map = pyramidOf(sampleRoom(rng, 6000, false));
  for (const Vec3& shift : {Vec3(1.23, -0.41, 0.35), Vec3(-2.1, 0.3, -0.2), Vec3(0.05, 0.0, 0.0)}) {
    // The query is the room seen from a rig that moved by `shift`: its points are the room's minus it.
    std::vector<Vec3> q = sampleRoom(rng, 400, false);
    for (auto& p : q) p -= shift;
    const auto r = map.search(q, Vec3::Zero(), 3.0);
    EXPECT_LT((r.t - shift).cwiseAbs().maxCoeff(), 0.16) << "shift " << shift.transpose() << " found " << r.t.transpose();
    EXPECT_EQ(r.points, 400);
    EXPECT_GE(r.hits, 360);  // nearly every query point lies on a mapped surface at the right shift
  }
}

TEST(OccupancySearch, CoarseToFineReachesTheBruteForceOptimum) {
  std::mt19937 rng(5);
  const OccupancyPyramid map = pyramidOf(sampleRoom(rng, 6000, false));
  std::vector<Vec3> q = sampleRoom(rng, 200, false);
  const Vec3 shift(0.7, -0.35, 0.2);
  for (auto& p : q) p -= shift;
  const double radius = 1.2, step = map.cellSize(0);
  // Brute force: every translation of the finest grid in the cube, scored at the finest level.
  auto hits = [&](const Vec3& t) {
    OccupancyPyramid::Result one = map.search(q, t, 0.0);  // radius 0: scores t alone
    return one.hits;
  };
  int best = -1;
  const int n = static_cast<int>(radius / step);
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k) best = std::max(best, hits(Vec3(i, j, k) * step));
  const auto r = map.search(q, Vec3::Zero(), radius);
  EXPECT_GE(r.hits, best - 2) << "the pyramid's answer scores within 1 % of the best candidate";
  EXPECT_EQ(hits(r.t), r.hits);
}

TEST(OccupancySearch, AnAmbiguousDirectionKeepsThePrediction) {
  // A corridor (floor and two walls along x), mapped far beyond the query's reach: a shift along x is
  // invisible, across it is not.
  std::mt19937 rng(7);
  const OccupancyPyramid map = pyramidOf(sampleRoom(rng, 20000, true, 30.0));
  std::vector<Vec3> q = sampleRoom(rng, 300, true, 8.0);
  const Vec3 shift(1.5, 0.45, 0.3);
  for (auto& p : q) p -= shift;
  const Vec3 prediction(0.4, 0.0, 0.0);
  const auto r = map.search(q, prediction, 2.0);
  // Along the axis the prediction stands, up to the sampling noise of two finest cells (the shift is
  // 1.5 m).
  EXPECT_NEAR(r.t.x(), prediction.x(), 0.31);
  EXPECT_NEAR(r.t.y(), shift.y(), 0.16);
  EXPECT_NEAR(r.t.z(), shift.z(), 0.16);
}

TEST(OccupancySearch, EmptyInputsReturnTheCentreAndBadArgumentsThrow) {
  OccupancyPyramid empty(0.2, 3);
  EXPECT_TRUE(empty.empty());
  const Vec3 c(1, 2, 3);
  EXPECT_EQ(empty.search({Vec3::Zero()}, c, 1.0).t, c);
  OccupancyPyramid one(0.2, 3);
  one.insert(Vec3::Zero());
  one.insert(Vec3(NAN, 0, 0));  // ignored
  EXPECT_EQ(one.occupiedCells(0), 27u);  // a point marks its cell and the 26 around it
  EXPECT_EQ(one.search({}, c, 1.0).t, c);
  EXPECT_EQ(one.search({Vec3::Zero()}, c, -1.0).t, c);
  EXPECT_THROW(OccupancyPyramid(0.0, 3), std::invalid_argument);
  EXPECT_THROW(OccupancyPyramid(0.1, 0), std::invalid_argument);
  EXPECT_THROW(OccupancyPyramid(0.1, 13), std::invalid_argument);
}

TEST(OccupancySearch, ScoreCountsHitsAndStopsWhenABarCannotBeReached) {
  OccupancyPyramid map(0.2, 3);
  map.insert(Vec3::Zero());  // marks [-0.2, 0.4) per axis at the finest level
  const std::vector<Vec3> pts{Vec3(0.1, 0, 0), Vec3(0.3, 0, 0), Vec3(5, 0, 0), Vec3(6, 0, 0), Vec3(0, 0.1, 0)};
  EXPECT_EQ(map.levels(), 3);
  EXPECT_EQ(map.score(pts, Vec3::Zero(), 0), 3);
  EXPECT_EQ(map.score(pts, Vec3(10, 0, 0), 0), 0);
  EXPECT_EQ(map.score(pts, Vec3::Zero(), 0, 3), 3);  // reachable: counted to the end
  EXPECT_LT(map.score(pts, Vec3::Zero(), 0, 4), 4);  // unreachable: less than the bar
  EXPECT_EQ(map.score(pts, Vec3::Zero(), 2), 3);     // coarser cells of 0.8 m: the far points still miss
}
