// Plane association shared by the in-process voxel map and the estimator's copy of a submap
// (docs/algorithms.md section 2, "Association").
//
// PlaneFinder is what the LiDAR update and the visual normal refinement need from a map: the most
// probable plane for a world point with covariance. VoxelMap implements it over its octrees;
// PlaneIndex implements it over a flat list of plane leaves per root voxel (the planes of a submap
// that the map server sent), with the same gates, the same score and the same one-neighbour rule, so
// both give the same plane for the same leaves.
#pragma once

#include "livo/map/plane.hpp"
#include "livo/map/point_cov.hpp"
#include "livo/map/voxel_key.hpp"

#include <array>
#include <cstddef>
#include <functional>
#include <unordered_map>
#include <vector>

namespace livo {

struct PlaneMatch {
  const Plane* plane = nullptr;
  double distance = 0.0;     ///< signed n^T p + d, m
  double sigma_l = 0.0;      ///< variance of the distance, m^2
  double probability = 0.0;  ///< sigma_l^-1/2 exp(-d^2 / (2 sigma_l))
};

class PlaneFinder {
 public:
  virtual ~PlaneFinder() = default;
  /// Most probable plane for a query point (docs/algorithms.md section 2, "Association"): every plane of
  /// the point's root voxel is scored (scorePlaneCandidate: 3-radius and 3-sigma gates, highest
  /// probability wins); if none is accepted (or the voxel does not exist), those of ONE neighbour
  /// root voxel (neighbourVoxelKey). False when no plane passes the gates. The rule is written once,
  /// in CachedAssociation::find; this is its one-shot use.
  bool findBestPlane(const PointWithCov& pw, PlaneMatch& out) const;

  // What a map provides for the search.
  /// Edge of the root voxels, m.
  virtual double rootVoxelSize() const = 0;
  /// Gate width of scorePlaneCandidate, sigmas.
  virtual double sigmaNum() const = 0;
  /// Calls f(plane) for every plane of root voxel `key`, in findBestPlane's order (nothing when the
  /// voxel does not exist). Plane addresses stay valid until the map changes.
  virtual void visitPlanes(const VoxelKey& key, const std::function<void(const Plane&)>& f) const = 0;
  /// Calls f(root key, plane) for every plane the map holds (any order).
  virtual void forEachPlane(const std::function<void(const VoxelKey&, const Plane&)>& f) const = 0;
};

/// One point's association across the iterations of an update against a map that does not change
/// meanwhile: find() gives exactly PlaneFinder::findBestPlane's answer, but keeps the candidate
/// planes of the point's root voxel (and of its neighbour, once needed) while the point stays in the
/// same voxel with the same neighbour, so that later iterations only re-score them (no hash lookup,
/// no octree walk). A voxel with more than kMaxCached planes is searched afresh every time.
class CachedAssociation {
 public:
  static constexpr int kMaxCached = 8;
  bool find(const PlaneFinder& finder, const PointWithCov& pw, PlaneMatch& out);
  /// After find(): the root voxel of the point it was given holds at least one plane (the map covers
  /// the point, whether or not a plane passed the gates).
  bool covered() const { return own_.n > 0; }

 private:
  struct Candidates {
    std::array<const Plane*, kMaxCached> planes;  // the first n are set
    int n = -1;  ///< -1: not fetched; kMaxCached + 1: too many (search afresh)
    void fetch(const PlaneFinder& finder, const VoxelKey& key);
    /// Scores the candidates (or, when too many, the voxel afresh) into `out`; true when one passed.
    bool best(const PlaneFinder& finder, const VoxelKey& key, const PointWithCov& pw, PlaneMatch& out) const;
  };
  VoxelKey own_key_, near_key_;
  bool has_near_ = false;
  Candidates own_, near_;
};

/// Scores one candidate plane for `pw`: accepted when the in-plane distance
/// sqrt(|p - q|^2 - d^2) <= sigma_num * radius and |d| < sigma_num * sqrt(sigma_l), with
/// sigma_l = J Sigma_nq J^T + n^T Sigma_w n. Replaces `best` when accepted and (no `have_best` or)
/// strictly more probable. Returns true when `best` was replaced.
bool scorePlaneCandidate(const Plane& plane, const PointWithCov& pw, double sigma_num, bool have_best,
                         PlaneMatch& best);

/// The one neighbour root voxel tried when a point's own voxel gives no plane: +1 along each axis
/// where the point lies in the upper quarter of its voxel, -1 in the lower quarter. False when the
/// point is in no outer quarter (then `out` is its own key).
bool neighbourVoxelKey(const Vec3& p, double voxel_size, VoxelKey& out);

/// True when `p` can be keyed at `voxel_size` (finite and |p / s| < 2^52).
bool keyablePoint(const Vec3& p, double voxel_size);

/// Flat plane leaves per root voxel (e.g. a received submap), searched by PlaneFinder::findBestPlane.
class PlaneIndex : public PlaneFinder {
 public:
  /// Throws std::invalid_argument unless voxel_size_m > 0 and sigma_num > 0.
  PlaneIndex(double voxel_size_m, double sigma_num);
  void add(const VoxelKey& key, const Plane& plane);
  void clear();
  /// Replaces the voxel size (keys of later add() calls must use it); clears the index.
  void reset(double voxel_size_m);
  double rootVoxelSize() const override { return voxel_size_; }
  double sigmaNum() const override { return sigma_num_; }
  void visitPlanes(const VoxelKey& key, const std::function<void(const Plane&)>& f) const override;
  void forEachPlane(const std::function<void(const VoxelKey&, const Plane&)>& f) const override;
  std::size_t numPlanes() const { return planes_; }
  std::size_t numVoxels() const { return voxels_.size(); }
  double voxelSize() const { return voxel_size_; }

 private:
  double voxel_size_;
  double sigma_num_;
  std::unordered_map<VoxelKey, std::vector<Plane>, VoxelKeyHash> voxels_;
  std::size_t planes_ = 0;
};

}  // namespace livo
