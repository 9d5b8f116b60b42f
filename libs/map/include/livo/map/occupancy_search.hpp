// Correlative translation search over an occupancy pyramid (coarse to fine), for registrations whose
// prediction may be metres off: the first LiDAR fixes of a rig that starts moving, when nothing yet
// says how fast it goes. Point-to-plane registration converges only within about a voxel of the
// truth; this search finds that basin.
//
// The map's points mark cells at `levels` resolutions, finest_m * 2^k, each point its own cell and
// the 26 neighbours (a surface sampled at other spots by the next sweep still scores). A search scores
// a translation t by how many of the query points (already rotated into the map frame) fall in marked
// cells after adding t. It evaluates every t of a grid with the coarsest useful cell as its step over the whole
// search cube, then refines around the best at each finer level (5 x 5 x 5 candidates, the level's
// cell as the step). Ties go to the translation nearest the search centre (the prediction), so a
// geometry that cannot tell translations apart (a corridor's axis) keeps the prediction.
#pragma once

#include "livo/common/so3.hpp"
#include "livo/map/voxel_key.hpp"

#include <unordered_set>
#include <vector>

namespace livo {

class OccupancyPyramid {
 public:
  /// Cells of finest_m, 2 finest_m, ... (levels of them). finest_m > 0, levels in [1, 12].
  explicit OccupancyPyramid(double finest_m = 0.1, int levels = 6);

  void insert(const Vec3& p_world);  ///< non-finite points are ignored
  void clear();
  bool empty() const { return levels_.front().empty(); }
  std::size_t occupiedCells(int level) const { return levels_.at(static_cast<std::size_t>(level)).size(); }
  double cellSize(int level) const;

  struct Result {
    Vec3 t = Vec3::Zero();  ///< the best translation
    int hits = 0;           ///< query points in occupied finest cells at t
    int points = 0;         ///< query points scored
  };
  /// The translation within the cube |t - center|_inf <= radius_m that puts the most `pts` in occupied
  /// cells. Points are used as given (the caller subsamples: the cost is points x candidates).
  Result search(const std::vector<Vec3>& pts, const Vec3& center, double radius_m) const;

  /// How many of `pts` + t fall in occupied cells of `level` (0: finest): the score of one candidate,
  /// for searches over more than translation (scan_registration.hpp adds rotation). With `at_least`
  /// > 0 the count stops as soon as it cannot reach at_least any more and returns what it has (less
  /// than at_least): a candidate that cannot beat the ones kept costs less.
  int score(const std::vector<Vec3>& pts, const Vec3& t, int level, int at_least = 0) const;
  int levels() const { return static_cast<int>(levels_.size()); }

 private:
  double finest_m_;
  std::vector<std::unordered_set<VoxelKey, VoxelKeyHash>> levels_;
};

}  // namespace livo
