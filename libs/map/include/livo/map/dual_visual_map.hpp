// The hybrid map's two visual maps (docs/algorithms.md "The two ideas", 3): the local visual map (points of
// the local cube, where new points go) and the long-term visual map (sparse points with a reference
// patch that left the local cube). Both are searched for the points in view (the same scan-voxel
// retrieval in each; per grid cell the nearest of the two winners); per-point operations go to the
// map that holds the point. Also the map server's side of the visual points of
// livo/map/map_protocol.hpp (copies per visual voxel, upserts, appended observations, next id).
// Which points live in which map is the slide policy's business (slide_policy.hpp).
//
// Pointers: VisualPoint* from retrieve / find stay valid until THAT point leaves its map:
// removeBadPoints() (the removed points), upsert() (the point with that id is replaced), clear(),
// and through HybridMap: update() (slides move points between the maps, the memory cap evicts them)
// and loading a map file. Callers must not change a visual point's p_world or id.
// Thread safety: const member functions may run concurrently; everything else needs exclusive access.
#pragma once

#include "livo/map/visual_map.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace livo {

class CameraModel;
class PlaneFinder;

class DualVisualMap {
 public:
  explicit DualVisualMap(const VisualMapConfig& config);

  // --- One frame's visual step (visual_step.hpp): retrieve, observe, remove, add -------------------
  /// VisualMap::retrieve on the local and on the long-term map; per grid cell one winner by winsCell
  /// (visual_map.hpp: the nearer, except that a point kept by the long-term map wins within
  /// vio.occlusion_depth_m of a local one), ordered by cell; the counters summed. A cell whose local
  /// winner is occluded may still receive the long-term winner (each map applies the occlusion test to
  /// its own winner).
  VisualRetrieval retrieve(const CameraModel& cam, const Pose& T_world_camera,
                           const std::vector<Vec3>& scan_points_world,
                           const std::vector<VoxelKey>* voxel_keys = nullptr);
  /// A point the photometric update used (`p` must come from this map), on the map that holds it:
  /// its error against `gate` (VisualMap::reportPhotometricError), then the observation at `px` of
  /// `gray` (VisualMap::addObservation) and, when one was added, reference selection and normal
  /// refinement against `planes` (VisualMap::refine; null: no normal refinement). True when an
  /// observation was added.
  bool observe(VisualPoint& p, double mean_sq_error, double gate, const Image& gray, const Pose& T_world_camera,
               const Vec2& px, float inv_exposure, Utime t, const PlaneFinder* planes);
  /// VisualMap::removeBadPoints on both maps; returns the count.
  std::size_t removeBadPoints();
  /// New visual points go to the local map (VisualMap::addPoints).
  int addPoints(const Image& gray, const CameraModel& cam, const Pose& T_world_camera, float inv_exposure, Utime t,
                const std::vector<NewPointCandidate>& candidates, const std::vector<bool>& occupied_cells);
  /// True when `p` is held by the long-term map.
  bool isLongterm(const VisualPoint& p) const { return longterm_.find(p.id) == &p; }

  // --- The map server's side of the protocol ---------------------------------------------------------
  /// Copies of every point of both maps in the given visual voxels (duplicate keys ignored), appended
  /// to `out`; returns the count appended.
  std::size_t copyPointsIn(const std::vector<VoxelKey>& visual_keys, std::vector<VisualPoint>& out) const;
  /// Replaces the point with p.id (in whichever map holds it) by `p`, or adds `p` to the local map
  /// when the id is unknown; a `p` without observations removes the point instead. Returns false when
  /// `p` was rejected (non-finite position, or a reference index outside its observations).
  bool upsert(VisualPoint p);
  /// Appends an observation to a point and refines it (refine with `lidar`); false when the id is
  /// unknown or the point is converged (frozen).
  bool appendObservation(std::int64_t id, const VisualObservation& obs, const PlaneFinder* lidar);
  /// Ids below this are taken in either map.
  std::int64_t nextId() const { return std::max(local_.nextId(), longterm_.nextId()); }

  // --- The two maps ---------------------------------------------------------------------------------
  const VisualMap& local() const { return local_; }
  const VisualMap& longterm() const { return longterm_; }
  /// Direct access for the slide policy, the memory cap, map files, tools and tests (e.g. inserting
  /// prepared points); the rules above still hold.
  VisualMap& local() { return local_; }
  VisualMap& longterm() { return longterm_; }

  /// Observations added through observe, upsert and appendObservation since construction (never
  /// reset; the byte estimate's growth term).
  std::size_t addedObservations() const { return added_observations_; }
  /// Empties both maps.
  void clear();

 private:
  VisualMap& holderOf(const VisualPoint& p) { return isLongterm(p) ? longterm_ : local_; }

  VisualMap local_;
  VisualMap longterm_;
  std::size_t added_observations_ = 0;
};

}  // namespace livo
