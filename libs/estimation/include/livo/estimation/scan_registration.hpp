// Scan-to-map registration without a motion model: a scan (points in the body frame) is registered
// against the voxel plane map from an initial pose and search bounds (a translation radius, a yaw and a
// tilt range), with no velocity or IMU input. It serves the registration of the first sweeps (the
// speed is unknown: at car speed and a sparse LiDAR a sweep may be a metre and tens of degrees from the
// last) and the recovery of a lost filter (re-registering a scan against the map the filter built).
//
// What it searches (SearchMap, kept beside the voxel map: fed the same registered points, or made from
// the map's plane leaves when its points are gone): an occupancy pyramid of the map's surfaces
// (OccupancyPyramid, cells of searchCell() = voxel / 2 times 2^k, each point marking its cell and the 26
// around it) and the map's surface normals (planar patches of the points at the voxel size, or the
// plane leaves), summed by direction (1 deg cells) per tile of 16 voxels.
//
// Method, coarse to fine (bounds of 0 trust that part of the initial pose R0, t0):
//  1a. Rotation from the normals (when yaw_rad or tilt_rad > 0 and the scan has at least kMinPatches
//      planar patches): the scan's planar patches (cubes of the voxel size with >= 6 points, smallest
//      eigenvalue below min_eigen_value + range_noise^2, middle one above 4 x the smallest and
//      (voxel / 8)^2; weight = point count; at most search_points of them) against the map's normals
//      within their reach of t0. A rotation R = Rz(yaw) Exp([a, b, 0]) R0 scores sum w_s f(R n_s),
//      f the map's normal density (both signs, dense grid over the unit cube, 3 x 3 x 3 box blur).
//      The tilt (a, b) first, from the elevations alone (a yaw leaves them unchanged): every 2 deg
//      within +-tilt_rad, then +-1 deg around the best. Then every yaw at 1 deg within +-yaw_rad, each
//      at the best of the tilts within +-3 deg of that one, on the density at 4 deg cells; the
//      kRotationPeaks best local maxima of that profile climb jointly in (yaw, a, b) at 1 deg steps on
//      the 2 deg density. In a building the yaw profile is nearly flat (floor and ceiling score the
//      same at every yaw; the walls repeat every 90 deg), so several peaks go on.
//  1b. Translation of each rotation peak by correlative search over the occupancy: every translation
//      of the finest level whose cell is at least a third of translation_m within the cube
//      |t - t0|_inf <= translation_m, the search_beam best refined at each finer level (27
//      neighbours at its cell), a candidate scoring the number of (at most search_points, spread over
//      the scan) points in occupied cells; a candidate's count stops once it cannot reach the beam, and
//      a peak that cannot come within kAmbiguousScore of an earlier peak's best is given up early. Ties
//      go to the candidate nearest the initial pose (a corridor's axis keeps the initial guess).
//      Without planar patches the yaw is searched by the occupancy instead (every yaw of the step that
//      moves a point at the 75th-percentile horizontal range by one cell, with the translations).
//      The max_hypotheses best (rotation, translation) by occupancy are the hypotheses.
//  2. Robust point-to-plane Gauss-Newton on the voxel map from each hypothesis (a later one only while
//     its occupancy is within kAmbiguousScore of the best, once one has registered). Right
//     perturbation R <- R Exp(dtheta), p <- p + dp (docs/algorithms.md sections 1, 2): for a point p_b
//     matched to the plane (n, d), z = n^T (R p_b + p) + d, dz/ddtheta = ([p_b]x R^T n)^T,
//     dz/ddp = n^T. Adaptive correspondence distance D: the first stage at max(voxel, 2 search cells)
//     (half a voxel when nothing was searched), each next one at min(D / 2, 3 robust sigmas
//     of the last residuals (1.4826 x median |z|)), never below sigma_num x sigma_point; the stage at
//     that floor is the last (twice the iterations). A point is matched to the nearest plane leaf
//     within D among the 3 x 3 x 3 root voxels around it whose in-plane gate (sigma_num radii) holds
//     it, leaves whose second spread sqrt(eig_mid) is below sigma_point left out (one scan line across
//     a voxel: no normal about that line). Weights: Cauchy w = 1 / (1 + z^2 / (c^2 s^2)) / s^2,
//     c = 2.3849, s^2 = var + (D / sigma_num)^2, var = J Sigma_nq J^T + n^T R Sigma_b R^T n +
//     residual_floor_var (the odometry's residual variance, section 2). Stages while D >= 2 x the floor
//     use a quarter of the points. A stage ends when the step is below a tenth of D (position; the
//     rotation at the points' median range), at the floor below a tenth of sigma_point or the lio
//     convergence thresholds, whichever is larger, or after stage_iterations.
//     Unconstrained directions: with M = sum n n^T / var over the matched points, eigen-directions u
//     with sqrt(lambda_u / trace M) < min_share are not updated (the step is solved with dp . u = 0);
//     after the last stage the position along them is set back to the initial pose's and the last
//     stage runs again with them frozen: a corridor's axis is not fixed.
//  3. Checks and output. A hypothesis registers when at the floor at least max(min_matches,
//     min_inlier_share x points) points matched, their RMS distance is at most maxRms() = sqrt(3)
//     sigma_point (residuals spread evenly over the final gate: no better than chance) and the last
//     stage converged; sigma_point = sqrt(range_noise_m^2 + min_eigen_value) (the LiDAR's range noise
//     and the map's plane thickness). Of the hypotheses, a registered one beats a failed one, then
//     the most matched points (all end at the same gate); two registered at poses apart (more than two
//     search cells or 4 deg) with matched counts within kAmbiguousScore, or two rotation peaks with
//     occupancy within kAmbiguousScore, set search_ambiguous: the map constrains little (a symmetric
//     room). The information of the pose is sum J^T w J over the final matches ([rotation, position],
//     right perturbation), divided by the mean z^2 / var when that exceeds 1 (real surfaces are less
//     flat than the planes' covariance says), with the unconstrained directions projected out.
//     weakest_share is sqrt(lambda_min / trace) of M (degeneracySigmaMin with the residual weights),
//     weakest_direction its eigenvector.
//
// Thresholds come from the configured sensor noise and voxel map (from(LioConfig, VoxelMapConfig,
// min_matches)); the other members are algorithm constants with defaults (no config keys).
//
// Figures (tests/test_estimation_registration.cpp, 2026-12-07, Release, 2 shared cores). Hilti 2021
// (177 real scans of a 64-beam LiDAR at 2 Hz, 74.5 m; up to 0.83 m, 48 deg of yaw and 16.5 deg of tilt
// between scans), each registered against the voxel map (0.4 m) of the ones before it, initial guess
// the previous registered pose, bounds 1 m / 60 deg / 20 deg, no IMU: 0 of 176 failed; RPE over 1 m
// 1.24 % and 0.117 deg/m, over 5 m 0.40 % and 0.032 deg/m; worst step 32.6 mm and 0.59 deg (the
// reference is a LiDAR-inertial odometry whose consecutive scans agree to a few centimetres); 160 ms
// a registration (max 431 ms). Ray-cast room (32 beams, 1 m / 30-48 deg / up to 8 deg of roll):
// within 7 mm and 0.06 deg; corridor: lateral position, height and rotation recovered, the axis
// reported (weakest share 0.04) and left at the initial guess.
#pragma once

#include "livo/common/so3.hpp"
#include "livo/estimation/lio_update.hpp"
#include "livo/map/occupancy_search.hpp"
#include "livo/map/plane_finder.hpp"
#include "livo/map/voxel_map.hpp"
#include "livo/map/voxel_map_config.hpp"

#include <functional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace livo {

struct ScanRegistrationConfig {
  // From the configured sensor and map (from()):
  double range_noise_m = 0.02;       ///< lidar.range_noise_m, m
  double beam_noise_deg = 0.05;      ///< lidar.beam_noise_deg, degrees
  double residual_floor_var = 1e-4;  ///< lio.residual_floor_var, m^2
  double converge_rot_deg = 0.01;    ///< lio.converge_rot_deg: a step below this ...
  double converge_pos_m = 1.5e-4;    ///< lio.converge_pos_m: ... and this has converged
  double voxel_size_m = 0.5;         ///< voxel_map.voxel_size_m: the map's root voxel edge, m
  double min_eigen_value = 0.0025;   ///< voxel_map.min_eigen_value: the planes' thickness, m^2
  double sigma_num = 3.0;            ///< voxel_map.sigma_num: association gates, sigmas
  int min_matches = 20;              ///< lio.min_matches: fewer matched points is a failure

  // Algorithm constants (no config keys):
  double search_cell_m = 0.0;  ///< finest cell of the search map, m; 0: voxel_size_m / 2
  int search_levels = 5;       ///< search map levels (cells search_cell_m x 2^k)
  int search_points = 256;     ///< scan points (and planar patches) scored per candidate, spread over the scan
  int search_beam = 8;         ///< candidates kept per level
  int max_hypotheses = 3;      ///< (rotation, translation) hypotheses refined at most, best occupancy first
  int max_points = 4000;       ///< refinement points at most (thinned to one per cube, then strided)
  int stage_iterations = 8;    ///< Gauss-Newton iterations per correspondence-distance stage
  double cauchy_c = 2.3849;    ///< Cauchy kernel width in sigmas (95 % efficiency on Gaussian noise)
  /// A translation direction whose share sqrt(lambda / trace) of the matched normals' scatter (weights
  /// 1 / var) is below this is unconstrained (the LiDAR update's kMinShare): not updated, no
  /// information.
  double min_share = 0.1;
  double min_inlier_share = 0.2;  ///< matched points at least this share of the refinement points

  /// The thresholds from the odometry's configuration (sensor noise, convergence, voxel map, min_matches).
  static ScanRegistrationConfig from(const LioConfig& lio, const VoxelMapConfig& map, int min_matches);
  /// sqrt(range_noise_m^2 + min_eigen_value): a matched point's distance to its plane, m.
  double pointSigma() const;
  /// sqrt(3) pointSigma(): the largest RMS residual of a successful registration, m (residuals spread
  /// evenly over the final gate of +-3 pointSigma() have this RMS: matches no better than chance).
  double maxRms() const;
  double searchCell() const { return search_cell_m > 0 ? search_cell_m : 0.5 * voxel_size_m; }
};

/// Search bounds around the initial pose. 0 trusts that part of the initial pose.
struct SearchBounds {
  double translation_m = 0.0;  ///< half edge of the translation cube, m
  double yaw_rad = 0.0;        ///< yaw range either side of the initial rotation, about world z, rad
  double tilt_rad = 0.0;       ///< roll / pitch range either side, about world x and y, rad
};

enum class RegistrationFailure {
  None,
  TooFewPoints,   ///< the scan has fewer than min_matches usable points
  EmptyMap,       ///< the map holds no plane near the initial pose (nothing was matched)
  TooFewMatches,  ///< fewer than max(min_matches, min_inlier_share x points) points matched
  HighResidual,   ///< matched RMS above maxRms()
  NotConverged,   ///< the final stage did not converge
};
const char* toString(RegistrationFailure f);

struct ScanRegistrationResult {
  bool success = false;
  RegistrationFailure failure = RegistrationFailure::TooFewPoints;
  std::string reason;  ///< "" on success; else what failed, with the figures
  /// The registered body pose (world from body); the best estimate also when !success.
  Pose T_world_body = Pose::Identity();
  /// Information of the pose, [rotation, position] right perturbation (R Exp(dtheta), p + dp), from the
  /// final Jacobians; zero along the unconstrained directions.
  Mat6 information = Mat6::Zero();
  int points = 0;            ///< refinement points
  int matched = 0;           ///< of them matched to a plane in the final iteration (final gate)
  double rms_residual_m = 0.0;  ///< RMS point-to-plane distance of the matched points
  /// sqrt(lambda_min / trace) of M = sum n n^T / var over the matched points (degeneracySigmaMin with
  /// the residual weights), in [0, 1/sqrt(3)].
  double weakest_share = 0.0;
  Vec3 weakest_direction = Vec3::UnitX();  ///< world frame, unit: the least constrained translation
  /// Translation directions (world frame, unit) below min_share: the pose along them is the initial
  /// guess (or the search's), not a fix. Empty when every direction is constrained.
  std::vector<Vec3> unconstrained_directions;
  int iterations = 0;          ///< Gauss-Newton iterations of the kept hypothesis
  int hypotheses_tried = 0;    ///< hypotheses refined
  // The correlative search:
  bool searched = false;           ///< the occupancy search ran (translation, or yaw without normals)
  bool rotation_searched = false;  ///< the rotation came from the normals' search
  Pose T_search = Pose::Identity();  ///< the best hypothesis of the search (before refinement)
  int search_hits = 0, search_points = 0;  ///< its occupancy score: points in occupied finest cells, of the scored
  /// Two rotation hypotheses with occupancy within kAmbiguousScore, or two registered hypotheses at
  /// poses apart with matched counts within kAmbiguousScore: the map tells the poses apart little (a
  /// symmetric room). A translation the map leaves free is in unconstrained_directions instead.
  bool search_ambiguous = false;
};

/// Unit normals of planar patches: each cube of `cell` (m) holding at least 6 points whose scatter is
/// planar (smallest eigenvalue below min_eigen_value + range_noise^2: the map's plane thickness plus
/// the sensor's noise) and spread in two directions (middle eigenvalue above 4 x the smallest and
/// (cell / 8)^2: not a single scan line). Weight: the patch's point count.
struct NormalPatch {
  Vec3 normal = Vec3::UnitZ();
  Vec3 center = Vec3::Zero();
  double weight = 0.0;
};
std::vector<NormalPatch> planarPatches(const std::vector<Vec3>& points, double cell, double max_eigen_value);

/// What a registration searches, kept beside the voxel map (add what goes into the map) or made from
/// its planes: an occupancy pyramid of the map's surfaces (cells of searchCell() x 2^k, search_levels
/// levels) for translations, and the map's surface normals by tiles of 16 voxels for rotations.
class SearchMap {
 public:
  explicit SearchMap(const ScanRegistrationConfig& cfg);
  /// World points (e.g. a registered scan): one per finest cell of each call marks the pyramid, and
  /// their planar patches (planarPatches at the voxel size) add their normals.
  void addPoints(const std::vector<Vec3>& world);
  /// Every plane leaf of `map` (within `radius_m` of `center`; radius <= 0: all), sampled at the
  /// finest cell on its plane inside its octree cell: for a map whose points are gone (frozen
  /// leaves), e.g. a lost filter's map. Non-plane leaves are not represented.
  void addPlanes(const PlaneFinder& map, const Vec3& center = Vec3::Zero(), double radius_m = 0.0);
  void clear();
  bool empty() const { return pyramid_.empty(); }
  const OccupancyPyramid& pyramid() const { return pyramid_; }
  /// Calls f(normal, weight) for the normals added within `radius_m` of `center` (by tiles: a tile
  /// counts when its centre is within radius + its half diagonal).
  void forEachNormal(const Vec3& center, double radius_m, const std::function<void(const Vec3&, double)>& f) const;

 private:
  void addNormal(const Vec3& position, const Vec3& normal, double weight);

  OccupancyPyramid pyramid_;
  std::unordered_set<VoxelKey, VoxelKeyHash> seen_;  ///< finest cells inserted
  double voxel_m_, patch_eigen_;
  double tile_m_;
  /// Per tile, the normals' weights summed by direction (key of the normal at a 1 deg cell, the sign
  /// chosen so that z > 0, or y > 0 when z = 0, or x > 0 when both are 0).
  std::unordered_map<VoxelKey, std::unordered_map<VoxelKey, double, VoxelKeyHash>, VoxelKeyHash> normals_;
};

class ScanRegistration {
 public:
  /// Scores within this share of the best: a competitor (search_ambiguous; refined; searched to the end).
  static constexpr double kAmbiguousScore = 0.95;
  /// Fewer planar patches in the scan: the normals do not search the rotation (the occupancy searches
  /// the yaw instead).
  static constexpr std::size_t kMinPatches = 12;
  /// Yaw peaks of the normals whose translation is searched; the max_hypotheses with the best
  /// occupancy are refined.
  static constexpr int kRotationPeaks = 6;

  explicit ScanRegistration(ScanRegistrationConfig cfg);
  const ScanRegistrationConfig& config() const { return cfg_; }

  /// Registers `scan` (body frame, each point with its measurement covariance) against `map`,
  /// searching `search` (the same map's occupancy and normals) within `bounds` around `T_init` (world
  /// from body). Neither the map nor the search map is changed (the caller inserts a registered scan);
  /// calls may run concurrently on maps nobody modifies meanwhile.
  ScanRegistrationResult align(const std::vector<BodyPoint>& scan, const PlaneFinder& map, const SearchMap& search,
                               const Pose& T_init, const SearchBounds& bounds) const;
  /// The same for sensor-frame points (body = sensor): covariances from range_noise_m / beam_noise_deg.
  ScanRegistrationResult align(const std::vector<Vec3>& scan, const PlaneFinder& map, const SearchMap& search,
                               const Pose& T_init, const SearchBounds& bounds) const;

  /// Sensor-frame points with their covariance (pointCovarianceBody), points at the origin dropped.
  std::vector<BodyPoint> bodyPoints(const std::vector<Vec3>& scan) const;

 private:
  ScanRegistrationConfig cfg_;
};

}  // namespace livo
