// Visual map (docs/algorithms.md sections 4.2 and 5): visual points in a hash of root voxels, retrieved
// per frame from the voxels the current scan touches, created from plane-matched LiDAR points in free
// grid cells, with observation, reference-selection, normal-refinement and outlier rules.
//
// Fixes to the reference code: floor keys everywhere (no off-by-one voxel for negative coordinates),
// the LiDAR plane is looked up with the LiDAR map's own voxel size, new points must lie in front of
// the camera (#421), the observation rules compare with the NEWEST observation, the border keeps
// every crop sample of every level inside the image (#69), observations keep small patch crops
// instead of whole images, and the map can be pruned (extract / idsOutsideBox / removeBadPoints).
//
// Ownership and pointers: every point lives in its own heap block (std::unique_ptr), so a
// VisualPoint* handed out (retrieve, find, forEach) stays valid until THAT point leaves the map
// (removeBadPoints, extract, clear, destruction); adding or removing other points never moves it.
// Callers may change a point's observations, normal, reference and counters through the pointer, but
// must not change p_world or id while it is in the map (extract, change, insert instead): the voxel
// index is keyed on them.
// Thread safety: const member functions may run concurrently; everything else needs exclusive access.
#pragma once

#include "livo/map/visual_map_config.hpp"
#include "livo/map/visual_point.hpp"
#include "livo/map/voxel_key.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <unordered_map>
#include <vector>

namespace livo {

class CameraModel;
class PlaneFinder;

/// Selection grid over the processed image: cells of cell_px x cell_px, the last row / column
/// possibly partial (ceil), so every pixel has a cell. Cell index = row * cols + col.
struct ImageGrid {
  int cell_px = 30;
  int cols = 0;
  int rows = 0;

  ImageGrid() = default;
  ImageGrid(int width, int height, int cell_px);
  int size() const { return cols * rows; }
  /// Cell of a pixel position, -1 outside the grid.
  int cellOf(const Vec2& px) const;
};

/// A LiDAR point that matched a plane: a candidate for a new visual point (docs/algorithms.md 5.1).
struct NewPointCandidate {
  Vec3 p_world = Vec3::Zero();
  Vec3 normal_world = Vec3::UnitZ();  ///< plane normal (any sign; flipped to face the camera)
  Mat3 cov_world = Mat3::Zero();      ///< position covariance, m^2
};

/// Counters of one retrieval.
struct VisualRetrievalStats {
  std::size_t visual_voxels = 0;    ///< distinct visual voxels holding a scan point
  std::size_t searched_points = 0;  ///< points in those voxels
  std::size_t in_image = 0;         ///< in front, inside the border, with a reference observation
  std::size_t occluded = 0;         ///< per-cell winners rejected by the depth test
  std::size_t selected = 0;         ///< points returned
};

/// What one retrieval found (VisualMap::retrieve, DualVisualMap::retrieve).
struct VisualRetrieval {
  ImageGrid grid;                    ///< the camera's selection grid
  std::vector<VisualPoint*> points;  ///< at most one per grid cell, ordered by cell
  std::vector<Vec2> pixels;          ///< their projections
  std::vector<bool> occupied;        ///< per grid cell (grid.size()): holds a returned point (for addPoints)
  VisualRetrievalStats stats;
  std::size_t longterm = 0;  ///< of `points`, those held by a long-term visual map
};

/// The selection grid of `cam` for cells of `cell_px` (VisualMapConfig::grid_cell_px).
ImageGrid selectionGrid(const CameraModel& cam, int cell_px);

/// The per-cell choice of retrieve (both maps, and their merge in DualVisualMap): does candidate `p`
/// at depth `z` beat the cell's current winner `best` (null: none) at depth `best_z`? The nearer point
/// wins (ties: smaller id), except that a point the long-term map kept (VisualPoint::from_longterm)
/// wins against one that it did not unless it lies farther by more than `same_surface_m` (the occlusion
/// test's depth, occlusion_depth_m): on a revisit, the point anchored to the earlier pass is used
/// rather than a new point on the same surface that carries the drift since then.
bool winsCell(const VisualPoint& p, double z, const VisualPoint* best, double best_z, double same_surface_m);

/// 21 public member functions (overloads counted once), one over the guideline of 20, for a reason:
/// the per-frame rules (retrieve, addPoints, addObservation, refine, reportPhotometricError,
/// removeBadPoints) work on the voxel index that the storage functions (insert, extract, find,
/// forEach, forEachInVoxel, idsOutsideBox, clear) keep consistent with the points' positions; a
/// separate storage class would expose that index to a second owner or forward every call to it.
/// The frame's visual step does not see this class: it works on DualVisualMap's four per-frame
/// calls (dual_visual_map.hpp).
class VisualMap {
 public:
  /// `longterm`: the long-term visual map: every point it takes (insert) is marked
  /// VisualPoint::from_longterm, the one place that mark is made.
  explicit VisualMap(VisualMapConfig config = {}, bool longterm = false);
  ~VisualMap();
  VisualMap(VisualMap&&) noexcept;
  VisualMap& operator=(VisualMap&&) noexcept;
  VisualMap(const VisualMap&) = delete;
  VisualMap& operator=(const VisualMap&) = delete;

  /// Visual points to use for one image (docs/algorithms.md 4.2). Only the visual voxels that hold a scan
  /// point (world frame, floor keys) are searched. A point qualifies when it has a reference
  /// observation, lies at depth z >= min_depth_m in the camera frame, projects and lies inside the
  /// border_px border; per grid cell the qualifying point with the smallest depth z wins (ties: smaller
  /// id; a point the long-term map kept goes first on the same surface: winsCell). A winner is occluded
  /// (dropped, its cell stays free) when a scan point projected within +-occlusion_window_px of its
  /// pixel (rounded) is closer in depth by more than occlusion_depth_m. With `voxel_keys` the visual
  /// voxels searched are those keys instead of the scan's (a frame whose LiDAR failed: the camera
  /// frustum, frustum_keys.hpp); the scan still serves the occlusion test (an empty scan: none).
  VisualRetrieval retrieve(const CameraModel& cam, const Pose& T_world_camera,
                           const std::vector<Vec3>& scan_points_world,
                           const std::vector<VoxelKey>* voxel_keys = nullptr);

  /// Creates visual points (docs/algorithms.md 5.1): a candidate qualifies when it lies at depth
  /// z >= min_depth_m (in front of the camera: fix of #421), projects inside the border and its cell
  /// is not occupied (`occupied_cells`: one flag per grid cell, or empty = all free). Per free cell the
  /// candidate with the highest Shi-Tomasi score (> min_shi_tomasi) is kept. Each new point gets a new
  /// id, the plane normal flipped to face the camera, and one observation (the patch pyramid of
  /// `gray` at its pixel), which is its reference. Returns the number created.
  /// Throws std::invalid_argument when `gray` is not Gray8 of the camera's size or occupied_cells has
  /// the wrong size.
  int addPoints(const Image& gray, const CameraModel& cam, const Pose& T_world_camera, float inv_exposure,
                Utime t, const std::vector<NewPointCandidate>& candidates,
                const std::vector<bool>& occupied_cells);

  /// Adds an observation of `p` at pixel `px` of `gray` (docs/algorithms.md 5.2) when, compared with the
  /// NEWEST observation (obs.back()), the camera moved more than new_obs_min_translation_m, the view
  /// ray from the point turned more than new_obs_min_angle_deg, or the pixel moved more than
  /// new_obs_min_pixel_shift_px (always when the point has none). Converged points are frozen (no new
  /// observations). Beyond max_observations the lowest-scoring observation is dropped (scores
  /// recomputed as in refine), never the reference nor the new one; the reference index follows.
  /// Sets p.last_seen = t. Returns true when an observation was added.
  bool addObservation(VisualPoint& p, const Image& gray, const Pose& T_world_camera, const Vec2& px,
                      float inv_exposure, Utime t);

  /// Reference selection and normal refinement (docs/algorithms.md 5.3). Scores every observation:
  ///   score_i = mean_{j != i} |NCC(level-0 patch i, level-0 patch j)| + cos(ray_i, n),
  /// ray_i = unit vector from the point to camera i. The patches are compared without warping them
  /// into a common view, so NCC is only an approximation of photometric agreement (good for small
  /// viewpoint changes, biased low for large ones; this only ranks observations). The best becomes
  /// the reference. From refine_min_observations observations on, the normal is replaced by the
  /// LiDAR plane's (VoxelMap::findBestPlane: its 3-radius and 3-sigma gates, the map's own voxel size),
  /// with the sign of the previous normal; when it moved less than normal_converge and the point has
  /// at least converge_min_observations observations it is converged: only the reference
  /// observation is kept. `lidar_map` may be null (no normal refinement); a VoxelMap or a PlaneIndex of submap planes.
  void refine(VisualPoint& p, const PlaneFinder* lidar_map);

  /// Outlier bookkeeping (docs/algorithms.md 5.5): an update with mean_sq_error > gate counts as bad,
  /// anything else resets the count of consecutive bad updates.
  void reportPhotometricError(VisualPoint& p, double mean_sq_error, double gate);
  /// Removes the points that went over max_bad_updates consecutive bad updates (as reported through
  /// this map's reportPhotometricError since the last call) and are still over; returns the count.
  std::size_t removeBadPoints();

  // Housekeeping for the hybrid map.
  std::size_t size() const { return by_id_.size(); }
  /// Memory in bytes: both hash tables (buckets + nodes), each point (struct + observation vector
  /// capacity) and the voxel id lists, plus 16 bytes of allocator overhead per heap block (glibc).
  /// Walks every point: call at stats rate. The retrieval scratch buffers are not included (see
  /// scratchBytes), so this grows and shrinks with the points only.
  std::size_t bytes() const;
  /// Retrieval scratch memory: the sparse depth image (4 bytes per pixel, allocated by the first
  /// retrieve) and the voxel list.
  std::size_t scratchBytes() const;
  std::size_t numVoxels() const { return voxels_.size(); }
  void forEach(const std::function<void(const VisualPoint&)>& f) const;
  void forEach(const std::function<void(VisualPoint&)>& f);
  /// Ids of the points whose root voxel centre lies outside the axis-aligned cube of half edge
  /// `half_edge_m` around `center` (same criterion as VoxelMap::removeOutsideBox).
  std::vector<std::int64_t> idsOutsideBox(const Vec3& center, double half_edge_m) const;
  /// Removes a point and hands it over (null when the id is unknown).
  std::unique_ptr<VisualPoint> extract(std::int64_t id);
  /// Takes a point (e.g. from another VisualMap) keeping its id. Returns false (point dropped) when it
  /// is null, its position is not finite or its id is already used here. Later ids stay above it.
  bool insert(std::unique_ptr<VisualPoint> point);
  /// Calls f for every point of one visual voxel (nothing when the voxel is empty).
  void forEachInVoxel(const VoxelKey& key, const std::function<void(const VisualPoint&)>& f) const;
  /// The id the next created point gets; raiseNextId() makes it at least `next` (ids below are taken
  /// elsewhere, e.g. in a map server's maps).
  std::int64_t nextId() const { return next_id_; }
  void raiseNextId(std::int64_t next) { next_id_ = std::max(next_id_, next); }
  VisualPoint* find(std::int64_t id);
  const VisualPoint* find(std::int64_t id) const;
  void clear();

  VoxelKey keyOf(const Vec3& p) const { return VoxelKey::fromPoint(p, config_.voxel_size_m); }
  const VisualMapConfig& config() const { return config_; }

 private:
  /// The searched voxels into searched_; returns their count.
  std::size_t collectSearchedVoxels(const std::vector<Vec3>& scan_points_world, const std::vector<VoxelKey>* voxel_keys);
  void rasterDepth(const CameraModel& cam, const Pose& T_camera_world, const std::vector<Vec3>& scan_points_world);
  /// Scores every observation of p (see refine) and returns the index of the best (-1: none).
  int scoreObservations(VisualPoint& p) const;
  void index(VisualPoint* p);
  void unindex(const VisualPoint* p);

  VisualMapConfig config_;
  bool longterm_ = false;
  std::unordered_map<std::int64_t, std::unique_ptr<VisualPoint>> by_id_;
  std::unordered_map<VoxelKey, std::vector<VisualPoint*>, VoxelKeyHash> voxels_;
  std::int64_t next_id_ = 1;
  std::vector<std::int64_t> suspects_;  ///< ids whose bad-update count went over the limit

  // Scratch of retrieve (kept to avoid reallocations).
  std::vector<float> depth_;        ///< sparse depth image, 0 = no scan point
  std::vector<int> depth_touched_;  ///< pixels set in depth_ (reset after each call)
  std::vector<const std::vector<VisualPoint*>*> searched_;  ///< visual voxels to search
};

}  // namespace livo
