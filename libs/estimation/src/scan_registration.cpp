#include "livo/estimation/scan_registration.hpp"

#include "scan_correlative_search.hpp"
#include "scan_rotation_search.hpp"

#include "livo/map/point_cov.hpp"
#include "livo/map/voxel_key.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace livo {

ScanRegistrationConfig ScanRegistrationConfig::from(const LioConfig& lio, const VoxelMapConfig& map, int min_matches) {
  ScanRegistrationConfig c;
  c.range_noise_m = lio.range_noise_m;
  c.beam_noise_deg = lio.beam_noise_deg;
  c.residual_floor_var = lio.residual_floor_var;
  c.converge_rot_deg = lio.converge_rot_deg;
  c.converge_pos_m = lio.converge_pos_m;
  c.voxel_size_m = map.voxel_size_m;
  c.min_eigen_value = map.min_eigen_value;
  c.sigma_num = map.sigma_num;
  c.min_matches = min_matches;
  return c;
}

double ScanRegistrationConfig::pointSigma() const {
  return std::sqrt(range_noise_m * range_noise_m + min_eigen_value);
}

double ScanRegistrationConfig::maxRms() const { return std::sqrt(3.0) * pointSigma(); }

const char* toString(RegistrationFailure f) {
  switch (f) {
    case RegistrationFailure::None: return "registered";
    case RegistrationFailure::TooFewPoints: return "too few points";
    case RegistrationFailure::EmptyMap: return "no map planes near the initial pose";
    case RegistrationFailure::TooFewMatches: return "too few matched points";
    case RegistrationFailure::HighResidual: return "high residual";
    case RegistrationFailure::NotConverged: return "not converged";
  }
  return "?";
}

// ----------------------------------------------------------------------------------- ScanRegistration

namespace {

using namespace scan_detail;

using Vec6d = Eigen::Matrix<double, 6, 1>;


/// One refinement (header, steps 2 and 3) from pose T.
struct Refinement {
  Pose T = Pose::Identity();
  Mat6 H = Mat6::Zero();  ///< sum J^T w J at the final iteration
  double chi2_per_point = 0.0;
  int matched = 0;
  double rms = 0.0;
  double gate = 0.0;  ///< the final correspondence distance, m
  /// sum w n n^T over the matched normals, w = 1 / var: the translation part of the information's shape
  Mat3 scatter = Mat3::Zero();
  std::vector<Vec3> frozen;
  int iterations = 0;
  bool converged = false;
};

class Refiner {
 public:
  Refiner(const ScanRegistrationConfig& cfg, const PlaneFinder& map, const std::vector<BodyPoint>& pts)
      : cfg_(cfg), map_(map), pts_(pts) {
    // The wide stages only have to reach the basin: a quarter of the points.
    const std::size_t stride = std::max<std::size_t>(1, pts_.size() / std::max(1, cfg_.max_points / 4));
    for (std::size_t i = 0; i < pts_.size(); i += stride) coarse_.push_back(pts_[i]);
    // A typical lever arm: the median range of the points (rotation steps are compared at it).
    std::vector<double> r;
    for (const BodyPoint& p : pts_) r.push_back(p.p_imu.norm());
    if (!r.empty()) {
      std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
      lever_ = std::max(1.0, r[r.size() / 2]);
    }
  }

  /// Stages of shrinking correspondence distance D from `D0`: each runs until its step is small, then
  /// D becomes the smaller of D / 2 and 3 robust sigmas of its residuals (1.4826 x their median
  /// absolute value), never below sigma_num x pointSigma(); the stage at that floor is the last.
  Refinement run(const Pose& T_start, const Pose& T_init, double D0) const {
    Refinement r;
    r.T = T_start;
    const double floor_gate = cfg_.sigma_num * cfg_.pointSigma();
    double D = std::max(D0, floor_gate);
    for (int guard = 0; guard < 16; ++guard) {
      const bool last = D <= floor_gate * (1 + 1e-9);
      const double robust_sigma = stage(r, D, last ? 2 * cfg_.stage_iterations : cfg_.stage_iterations);
      if (r.matched < 6) return r;
      if (last) break;
      D = std::max(floor_gate, std::min(0.5 * D, 3.0 * robust_sigma));
    }
    r.gate = D;
    if (!r.frozen.empty()) {
      // Nothing is claimed along an unconstrained direction: the position along it goes back to the
      // initial pose's, and the last stage runs again with it frozen.
      Vec3 p = r.T.translation();
      for (const Vec3& u : r.frozen) p -= u * u.dot(p - T_init.translation());
      r.T.translation() = p;
      stage(r, D, 2 * cfg_.stage_iterations, /*keep_frozen=*/true);
    }
    return r;
  }

 private:
  struct Sums {
    Mat6 H = Mat6::Zero();
    Vec6d g = Vec6d::Zero();
    double sq = 0.0, chi2 = 0.0;
    int matched = 0;
    Mat3 scatter = Mat3::Zero();
    std::vector<double> abs_z;
  };

  /// Associates every point at T with correspondence distance D and sums the weighted normal equations.
  Sums associate(const Pose& T, double D) const {
    Sums s;
    const Mat3 R = T.linear();
    const double vs = map_.rootVoxelSize();
    const double inflate = std::pow(D / cfg_.sigma_num, 2);
    const double c2 = cfg_.cauchy_c * cfg_.cauchy_c;
    // The wide stages (D at least twice the floor gate) use the subset.
    const bool wide = D >= 2.0 * cfg_.sigma_num * cfg_.pointSigma();
    // A plane whose points spread less than their own noise in its second direction (one scan line
    // across a voxel) has no defined normal about that line: not used.
    const double min_spread = cfg_.pointSigma() * cfg_.pointSigma();
    const std::vector<BodyPoint>& pts = wide ? coarse_ : pts_;
    std::vector<Candidates>& cache = wide ? coarse_cache_ : cache_;
    cache.resize(pts.size());
    // Within half a voxel of the point (D <= voxel / 2) the 2 x 2 x 2 root voxels nearest it hold every
    // plane that can match: they are set by the point's half-voxel cell. Farther, the 3 x 3 x 3 around
    // its root voxel.
    const bool block27 = D > 0.5 * vs;
    const double cell = block27 ? vs : 0.5 * vs;
    auto& shared = block27 ? planes27_ : planes8_;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const BodyPoint& bp = pts[i];
      const Vec3 pw = R * bp.p_imu + T.translation();
      if (!keyablePoint(pw, vs)) continue;
      // The candidate planes are fetched once per cell and call (the map does not change meanwhile),
      // and a point keeps its cell's list while it stays in the cell.
      const VoxelKey k = VoxelKey::fromPoint(pw, cell);
      Candidates& c = cache[i];
      if (!c.planes || c.block27 != block27 || c.key != k) {
        c.block27 = block27;
        c.key = k;
        auto it = shared.find(k);
        if (it == shared.end()) {
          std::vector<const Plane*> list;
          auto take = [&](const Plane& pl) {
            if (pl.eig_mid >= min_spread) list.push_back(&pl);
          };
          if (block27) {
            for (int a = -1; a <= 1; ++a)
              for (int b = -1; b <= 1; ++b)
                for (int l = -1; l <= 1; ++l) map_.visitPlanes({k.x + a, k.y + b, k.z + l}, take);
          } else {
            // Half-voxel cell h: root voxel floor(h / 2); the neighbour on each axis towards h's side.
            auto root = [](std::int64_t h) { return h >= 0 ? h / 2 : -((-h + 1) / 2); };
            const VoxelKey r{root(k.x), root(k.y), root(k.z)};
            const int dx = k.x - 2 * r.x == 0 ? -1 : 1, dy = k.y - 2 * r.y == 0 ? -1 : 1, dz = k.z - 2 * r.z == 0 ? -1 : 1;
            for (int a = 0; a < 2; ++a)
              for (int b = 0; b < 2; ++b)
                for (int l = 0; l < 2; ++l) map_.visitPlanes({r.x + a * dx, r.y + b * dy, r.z + l * dz}, take);
          }
          it = shared.emplace(k, std::move(list)).first;
        }
        c.planes = &it->second;
      }
      // The nearest plane within D whose in-plane gate (sigma_num radii) holds the point.
      const Plane* plane = nullptr;
      double z = 0.0, best = D;
      for (const Plane* pl : *c.planes) {
        const double dist = pl->signedDistance(pw);
        if (std::abs(dist) >= best) continue;
        const double in_plane_sq = std::max((pw - pl->center).squaredNorm() - dist * dist, 0.0);
        const double rg = cfg_.sigma_num * pl->radius;
        if (in_plane_sq > rg * rg) continue;
        best = std::abs(dist);
        plane = pl;
        z = dist;
      }
      if (!plane) continue;
      const Vec3& n = plane->normal;
      const double var = pointToPlaneVariance(*plane, pw, R * bp.cov_imu * R.transpose()) + cfg_.residual_floor_var;
      const double s2 = var + inflate;
      const double w = 1.0 / (1.0 + z * z / (c2 * s2)) / s2;
      Vec6d J;
      J.head<3>() = hat(bp.p_imu) * R.transpose() * n;
      J.tail<3>() = n;
      s.H.noalias() += w * J * J.transpose();
      s.g.noalias() += w * J * z;
      s.sq += z * z;
      s.chi2 += z * z / var;
      s.scatter.noalias() += (n * n.transpose()) / var;
      s.abs_z.push_back(std::abs(z));
      ++s.matched;
    }
    return s;
  }

  /// Translation directions whose share of the normals' scatter is below min_share.
  std::vector<Vec3> unconstrained(const Mat3& M) const {
    std::vector<Vec3> out;
    if (!(M.trace() > 0)) return out;
    const Eigen::SelfAdjointEigenSolver<Mat3> es(M);
    for (int i = 0; i < 3; ++i)
      if (std::sqrt(std::max(0.0, es.eigenvalues()(i)) / M.trace()) < cfg_.min_share)
        out.push_back(es.eigenvectors().col(i).normalized());
    return out;
  }

  /// Gauss-Newton iterations at correspondence distance D until the step is small: below a tenth of
  /// the gate (position, and rotation at the points' median range) and, at the floor gate, below a
  /// tenth of pointSigma() or the odometry's convergence thresholds, whichever is larger. Returns the
  /// robust sigma of the last iteration's residuals. The unconstrained directions are found anew in
  /// every iteration unless `keep_frozen`.
  double stage(Refinement& r, double D, int iterations, bool keep_frozen = false) const {
    const double floor_gate = cfg_.sigma_num * cfg_.pointSigma();
    const double small_pos = std::max(cfg_.converge_pos_m, 0.1 * (D > floor_gate * (1 + 1e-9) ? D : cfg_.pointSigma()));
    const double small_rot = std::max(cfg_.converge_rot_deg * M_PI / 180.0, small_pos / lever_);
    r.converged = false;
    double robust_sigma = 0.0;
    for (int it = 0; it < iterations; ++it) {
      Sums s = associate(r.T, D);
      ++r.iterations;
      r.matched = s.matched;
      r.scatter = s.scatter;
      if (s.matched < 6) {
        r.H.setZero();
        r.scatter.setZero();
        r.rms = 0.0;
        return 0.0;
      }
      r.rms = std::sqrt(s.sq / s.matched);
      r.chi2_per_point = s.chi2 / s.matched;
      r.H = s.H;
      std::nth_element(s.abs_z.begin(), s.abs_z.begin() + s.abs_z.size() / 2, s.abs_z.end());
      robust_sigma = 1.4826 * s.abs_z[s.abs_z.size() / 2];
      if (!keep_frozen) r.frozen = unconstrained(r.scatter);
      // Solve in the subspace orthogonal to the frozen translation directions.
      Eigen::Matrix<double, 6, Eigen::Dynamic> Q(6, 6 - static_cast<int>(r.frozen.size()));
      {
        Mat6 P = Mat6::Identity();
        for (const Vec3& u : r.frozen) {
          Vec6d e = Vec6d::Zero();
          e.tail<3>() = u;
          P -= e * e.transpose();
        }
        const Eigen::SelfAdjointEigenSolver<Mat6> es(P);
        Q = es.eigenvectors().rightCols(Q.cols());  // eigenvalue 1: the free subspace
      }
      const Eigen::MatrixXd Hq = Q.transpose() * s.H * Q;
      const Eigen::VectorXd y = Hq.ldlt().solve(-(Q.transpose() * s.g));
      Vec6d delta = Q * y;
      if (!delta.allFinite()) delta.setZero();
      r.T.linear() = r.T.linear() * expSO3(delta.head<3>());
      r.T.translation() += delta.tail<3>();
      if (delta.head<3>().norm() < small_rot && delta.tail<3>().norm() < small_pos) {
        r.converged = true;
        break;
      }
    }
    return robust_sigma;
  }

  const ScanRegistrationConfig& cfg_;
  const PlaneFinder& map_;
  const std::vector<BodyPoint>& pts_;
  std::vector<BodyPoint> coarse_;
  /// A point's candidate planes and the cell they were fetched for.
  struct Candidates {
    bool block27 = false;
    VoxelKey key;
    const std::vector<const Plane*>* planes = nullptr;
  };
  mutable std::vector<Candidates> cache_, coarse_cache_;
  /// The candidate planes by cell: root voxels (3 x 3 x 3 around) and half voxels (2 x 2 x 2 nearest).
  mutable std::unordered_map<VoxelKey, std::vector<const Plane*>, VoxelKeyHash> planes27_, planes8_;
  double lever_ = 10.0;
};

}  // namespace

ScanRegistration::ScanRegistration(ScanRegistrationConfig cfg) : cfg_(cfg) {
  if (!(cfg_.voxel_size_m > 0) || !(cfg_.range_noise_m > 0) || !(cfg_.min_eigen_value > 0) || !(cfg_.sigma_num > 0))
    throw std::invalid_argument("ScanRegistration: voxel size, range noise, min_eigen_value and sigma_num must be > 0");
  if (cfg_.search_levels < 1 || cfg_.search_levels > 12 || cfg_.search_points < 1 || cfg_.search_beam < 1 ||
      cfg_.max_hypotheses < 1 || cfg_.max_points < 6 || cfg_.stage_iterations < 1)
    throw std::invalid_argument("ScanRegistration: bad search or refinement sizes");
}

std::vector<BodyPoint> ScanRegistration::bodyPoints(const std::vector<Vec3>& scan) const {
  std::vector<BodyPoint> out;
  out.reserve(scan.size());
  for (const Vec3& p : scan)
    if (p.allFinite() && p.norm() > 1e-3) out.push_back({p, pointCovarianceBody(p, cfg_.range_noise_m, cfg_.beam_noise_deg)});
  return out;
}

ScanRegistrationResult ScanRegistration::align(const std::vector<Vec3>& scan, const PlaneFinder& map,
                                               const SearchMap& search, const Pose& T_init,
                                               const SearchBounds& bounds) const {
  return align(bodyPoints(scan), map, search, T_init, bounds);
}

ScanRegistrationResult ScanRegistration::align(const std::vector<BodyPoint>& scan, const PlaneFinder& map,
                                               const SearchMap& search, const Pose& T_init,
                                               const SearchBounds& bounds) const {
  ScanRegistrationResult res;
  res.T_world_body = T_init;
  res.T_search = T_init;
  std::vector<BodyPoint> pts;
  for (const std::size_t i : spread(scan, 0.25 * cfg_.voxel_size_m, cfg_.max_points)) pts.push_back(scan[i]);
  res.points = static_cast<int>(pts.size());
  auto fail = [&](RegistrationFailure f, const std::string& why) {
    res.success = false;
    res.failure = f;
    res.reason = std::string(toString(f)) + (why.empty() ? "" : ": " + why);
    return res;
  };
  if (res.points < std::max(cfg_.min_matches, 6))
    return fail(RegistrationFailure::TooFewPoints, std::to_string(res.points) + " points");

  // 1. The correlative search: rotation hypotheses from the normals, then the translation of each.
  struct Hypothesis {
    Pose T = Pose::Identity();
    int score = -1;
  };
  std::vector<Hypothesis> hyps;
  const double cell0 = search.pyramid().cellSize(0);
  const bool search_t = bounds.translation_m > 0 && !search.empty();
  const bool search_r = (bounds.yaw_rad > 0 || bounds.tilt_rad > 0) && !search.empty();
  std::vector<Vec3> q;  // the points the occupancy scores
  if (search_t || search_r)
    for (const std::size_t i : spread(scan, cell0, cfg_.search_points)) q.push_back(scan[i].p_imu);
  std::vector<Mat3> rotations{T_init.linear()};
  double occupancy_yaw = 0.0;  // yaw left to the occupancy search (when the normals cannot tell it)
  if (search_r) {
    std::vector<Vec3> body;
    body.reserve(scan.size());
    for (const BodyPoint& b : scan) body.push_back(b.p_imu);
    std::vector<NormalPatch> patches =
        planarPatches(body, cfg_.voxel_size_m, cfg_.min_eigen_value + cfg_.range_noise_m * cfg_.range_noise_m);
    double reach = 0.0;
    for (const NormalPatch& p : patches) reach = std::max(reach, p.center.norm());
    if (patches.size() > static_cast<std::size_t>(cfg_.search_points)) {
      std::vector<NormalPatch> sub;
      const double stride = double(patches.size()) / cfg_.search_points;
      for (int k = 0; k < cfg_.search_points; ++k) sub.push_back(patches[static_cast<std::size_t>(k * stride)]);
      patches.swap(sub);
    }
    // The map's normals around the initial position: their density (2 deg cells) and elevations.
    NormalDensity dens(2.0 * M_PI / 180.0), coarse(4.0 * M_PI / 180.0);
    ElevationHistogram elev;
    double map_weight = 0.0;
    search.forEachNormal(T_init.translation(), reach + bounds.translation_m, [&](const Vec3& n, double w) {
      dens.add(n, w);
      coarse.add(n, w);
      elev.add(n, w);
      map_weight += w;
    });
    if (patches.size() >= kMinPatches && map_weight > 0) {
      dens.blur();
      coarse.blur();
      elev.blur();
      const std::vector<RotCandidate> rc =
          rotationSearch(dens, coarse, elev, patches, T_init.linear(), std::max(0.0, bounds.yaw_rad),
                         std::max(0.0, bounds.tilt_rad), kRotationPeaks);
      rotations.clear();
      for (const RotCandidate& c : rc) {
        rotations.push_back(rotationOf(c, T_init.linear()));
        if (static_cast<int>(rotations.size()) >= kRotationPeaks) break;
      }
      res.rotation_searched = true;
    } else {
      occupancy_yaw = std::max(0.0, bounds.yaw_rad);  // too few planar patches: the occupancy searches yaw
    }
  }
  if (search_t || occupancy_yaw > 0) {
    res.searched = true;
    res.search_points = static_cast<int>(q.size());
    int floor_score = 0;  // rotations that cannot come near the best so far are given up early
    for (const Mat3& R : rotations) {
      Pose T0 = T_init;
      T0.linear() = R;
      double yaw_step0 = 0.0;
      std::vector<Candidate> cands = correlativeSearch(search.pyramid(), q, T0, SearchBounds{bounds.translation_m, occupancy_yaw},
                                                       cfg_.search_beam, yaw_step0, floor_score);
      if (!cands.empty())
        floor_score = std::max(floor_score, static_cast<int>(std::floor(kAmbiguousScore * cands.front().score)));
      if (cands.empty()) cands.push_back(Candidate{});
      // With the yaw left to the occupancy, its distinct candidates are the hypotheses; else its best.
      for (const Candidate& c : distinct(cands, occupancy_yaw > 0 ? cfg_.max_hypotheses : 1, cell0, yaw_step0)) {
        Hypothesis h;
        h.T.linear() = yawRotation(c.yaw) * R;
        h.T.translation() = T_init.translation() + c.t;
        h.score = c.score;
        hyps.push_back(h);
      }
    }
    // Best occupancy first (rotation hypotheses in their own order on ties).
    std::stable_sort(hyps.begin(), hyps.end(), [](const Hypothesis& a, const Hypothesis& b) { return a.score > b.score; });
    if (hyps.size() > static_cast<std::size_t>(cfg_.max_hypotheses)) hyps.resize(static_cast<std::size_t>(cfg_.max_hypotheses));
    // Another rotation hypothesis explaining the scan nearly as well: the map constrains the rotation little.
    if (hyps.size() > 1 && hyps[1].score >= kAmbiguousScore * hyps[0].score &&
        rotationAngle(hyps[0].T.linear().transpose() * hyps[1].T.linear()) > 2.0 * (2.0 * M_PI / 180.0))
      res.search_ambiguous = true;
    res.search_hits = hyps.front().score;
  } else {
    for (const Mat3& R : rotations) {
      Hypothesis h;
      h.T = T_init;
      h.T.linear() = R;
      hyps.push_back(h);
      if (static_cast<int>(hyps.size()) >= cfg_.max_hypotheses) break;
    }
  }
  res.T_search = hyps.front().T;

  // 2. Refinement from each distinct candidate until one passes the checks (3).
  const Refiner refiner(cfg_, map, pts);
  // The first correspondence distance: a voxel, or the search's quantisation (two finest cells) when
  // coarser; with no search (both bounds 0) half a voxel.
  const double start_gate =
      res.searched || res.rotation_searched ? std::max(cfg_.voxel_size_m, 2.0 * cell0) : 0.5 * cfg_.voxel_size_m;
  const int need = std::max(cfg_.min_matches, static_cast<int>(std::ceil(cfg_.min_inlier_share * res.points)));
  ScanRegistrationResult kept;
  bool have = false;
  for (const Hypothesis& hyp : hyps) {
    // Once one is registered, only the hypotheses the search could not rule out are refined: those
    // within kAmbiguousScore of the best occupancy.
    if (have && kept.success && hyp.score >= 0 && hyp.score < kAmbiguousScore * hyps.front().score) break;
    const Refinement r = refiner.run(hyp.T, T_init, start_gate);
    ScanRegistrationResult h = res;
    h.T_world_body = r.T;
    h.matched = r.matched;
    h.rms_residual_m = r.rms;
    h.iterations = r.iterations;
    h.unconstrained_directions = r.frozen;
    if (r.scatter.trace() > 0) {
      const Eigen::SelfAdjointEigenSolver<Mat3> es(r.scatter);
      h.weakest_share = std::sqrt(std::max(0.0, es.eigenvalues()(0)) / r.scatter.trace());
      h.weakest_direction = es.eigenvectors().col(0).normalized();
    }
    Mat6 info = r.H / std::max(1.0, r.chi2_per_point);
    if (!r.frozen.empty()) {
      Mat6 P = Mat6::Identity();
      for (const Vec3& u : r.frozen) {
        Vec6d e = Vec6d::Zero();
        e.tail<3>() = u;
        P -= e * e.transpose();
      }
      info = P * info * P;
    }
    h.information = 0.5 * (info + info.transpose());
    std::ostringstream why;
    if (r.matched == 0) {
      h.failure = RegistrationFailure::EmptyMap;
      why << "no point found a plane";
    } else if (r.matched < need) {
      h.failure = RegistrationFailure::TooFewMatches;
      why << r.matched << " of " << res.points << " points matched, need " << need;
    } else if (r.rms > cfg_.maxRms()) {
      h.failure = RegistrationFailure::HighResidual;
      why << "RMS " << r.rms << " m > " << cfg_.maxRms() << " m";
    } else if (!r.converged) {
      h.failure = RegistrationFailure::NotConverged;
      why << "no small step within " << 2 * cfg_.stage_iterations << " final iterations";
    } else {
      h.failure = RegistrationFailure::None;
    }
    h.success = h.failure == RegistrationFailure::None;
    h.reason = h.success ? std::string() : std::string(toString(h.failure)) + ": " + why.str();
    ++res.hypotheses_tried;
    // Every hypothesis is refined: a success beats a failure, then the most matched points (all end at
    // the same correspondence distance). Two successes that match about as many points at poses apart
    // make the result ambiguous.
    if (have && h.success && kept.success && std::min(h.matched, kept.matched) >= kAmbiguousScore * std::max(h.matched, kept.matched) &&
        ((h.T_world_body.translation() - kept.T_world_body.translation()).norm() > 2.0 * cell0 ||
         rotationAngle(h.T_world_body.linear().transpose() * kept.T_world_body.linear()) > 2.0 * (2.0 * M_PI / 180.0)))
      res.search_ambiguous = true;
    if (!have || (h.success && !kept.success) || (h.success == kept.success && h.matched > kept.matched)) {
      kept = std::move(h);
      have = true;
    }
  }
  kept.hypotheses_tried = res.hypotheses_tried;
  kept.search_ambiguous = res.search_ambiguous;
  return kept;
}

}  // namespace livo
