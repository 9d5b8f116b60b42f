#include "livo/estimation/filter_start.hpp"

#include "livo/estimation/undistort.hpp"
#include "livo/map/point_cov.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace livo {

void StartConfig::load(const ConfigNode& n) {
  n.get("init_max_speed_mps", max_speed_mps).get("init_max_tilt_deg", max_tilt_deg);
  n.check(std::isfinite(max_speed_mps) && max_speed_mps > 0 && max_speed_mps <= 100, "init_max_speed_mps",
          "must be in (0, 100] m/s (the fastest the rig moves at its start)");
  n.check(std::isfinite(max_tilt_deg) && max_tilt_deg >= 1 && max_tilt_deg <= 60, "init_max_tilt_deg",
          "must be in [1, 60] deg");
}

FilterStart::FilterStart(const ImuConfig& imu, StartConfig cfg, VoxelMapConfig map, LioConfig lio, int min_matches,
                         const Pose& T_imu_lidar)
    : imu_(imu), cfg_(cfg), map_cfg_(map), lio_(lio), min_matches_(min_matches), T_imu_lidar_(T_imu_lidar),
      map_(std::make_unique<VoxelMap>(map)), occupancy_(0.15, 5) {}

namespace {

/// Eigenvectors of the normals' scatter whose share sqrt(lambda / N) reaches `min_share`.
std::vector<Vec3> constrainedDirections(const Mat3& scatter, double total, double min_share) {
  std::vector<Vec3> dirs;
  if (!(total > 0)) return dirs;
  const Eigen::SelfAdjointEigenSolver<Mat3> es(scatter / total);
  for (int i = 0; i < 3; ++i)
    if (std::sqrt(std::max(0.0, es.eigenvalues()(i))) >= min_share) dirs.push_back(es.eigenvectors().col(i));
  return dirs;
}

double sweepSeconds(const std::vector<ImuTracePoint>& trace) {
  return trace.size() < 2 ? 0.0 : toSeconds(trace.back().utime - trace.front().utime);
}

}  // namespace

bool FilterStart::prior(const Frame& frame, NavState& x, StateCov& P, double& accel_scale) {
  for (const auto& s : frame.imu)
    if (samples_.empty() || s.utime > samples_.back().utime) samples_.push_back(s);
  const std::size_t keep = static_cast<std::size_t>(std::max(imu_.init_samples, 1));
  // The samples of this frame and, to reach init_samples, those just before it.
  std::size_t use = std::max(keep, frame.imu.size());
  while (samples_.size() > std::max<std::size_t>(use, 1)) samples_.pop_front();
  if (frame.imu.empty() || samples_.size() < keep) return false;
  use = samples_.size();

  // Rotate every sample's specific force into the body frame at the frame's first sample (gyro, bias
  // 0: over a fraction of a second a bias of 0.02 rad/s turns it by a fraction of a degree).
  const Utime t0 = frame.imu.front().utime;
  std::vector<Mat3> R(use);
  R[0] = Mat3::Identity();
  Mat3 R_t0 = Mat3::Identity();
  for (std::size_t k = 0; k + 1 < use; ++k) {
    const double dt = toSeconds(samples_[k + 1].utime - samples_[k].utime);
    R[k + 1] = R[k] * expSO3(0.5 * (samples_[k].gyro + samples_[k + 1].gyro) * dt);
  }
  for (std::size_t k = 0; k < use; ++k)
    if (samples_[k].utime <= t0) R_t0 = R[k];
  Vec3 raw = Vec3::Zero();
  for (const auto& s : samples_) raw += s.accel;
  raw /= double(use);
  if (!raw.allFinite() || !(raw.norm() > 1e-3)) return false;
  // An IMU reports m/s^2 or g: which one follows from the magnitude.
  accel_scale = raw.norm() < 4.0 ? imu_.gravity_m_s2 : 1.0;
  std::vector<Vec3> f(use);
  Vec3 mean = Vec3::Zero();
  for (std::size_t k = 0; k < use; ++k) {
    f[k] = R_t0.transpose() * R[k] * samples_[k].accel * accel_scale;
    mean += f[k];
  }
  mean /= double(use);
  double var_total = 0.0;
  for (const Vec3& v : f) var_total += (v - mean).squaredNorm();
  var_total /= double(std::max<std::size_t>(use - 1, 1));
  const double g = imu_.gravity_m_s2;
  const double sa = imu_.accelSampleSigma();
  // Beyond white noise: motion and vibration, which need not average out over the window.
  const double var_excess = std::max(0.0, var_total - 3.0 * sa * sa);
  // |f|^2 = |a_h|^2 + (g + a_v)^2: a norm above g is horizontal acceleration (or vertical; both count).
  const double accel_h2 = std::max(0.0, mean.squaredNorm() - g * g);
  const double sba = imu_.init_accel_bias_sigma_mps2;
  const double var_h_uncapped = sa * sa / double(use) + sba * sba + var_excess + accel_h2;
  const double max_h = g * std::tan(cfg_.max_tilt_deg * M_PI / 180.0);
  const double var_h = std::min(var_h_uncapped, max_h * max_h);
  // A tilt of the gravity vector also shortens its vertical part by about sigma_h^2 / (2 g).
  const double var_v = std::pow(var_h / (2.0 * g), 2) + 1e-5;

  x = NavState();
  x.utime = t0;
  const Vec3 up = mean.normalized();
  Mat3 P_g = Mat3::Zero();
  if (imu_.gravity_align) {
    x.R_world_imu = Quat::FromTwoVectors(up, Vec3::UnitZ()).toRotationMatrix();
    x.g_world = Vec3(0, 0, -g);
    P_g.diagonal() << var_h, var_h, var_v;
  } else {
    x.g_world = -g * up;
    P_g = var_h * (Mat3::Identity() - up * up.transpose()) + var_v * up * up.transpose();
  }
  using namespace sidx;
  P = initialCovariance();
  P.block<3, 3>(kRot, kRot) = Mat3::Identity() * 1e-8;  // the world frame's definition
  P.block<3, 3>(kPos, kPos) = Mat3::Identity() * 1e-8;
  const double sv = 0.5 * cfg_.max_speed_mps;
  P.block<3, 3>(kVel, kVel) = Mat3::Identity() * sv * sv;
  P.block<3, 3>(kBg, kBg) = Mat3::Identity() * std::pow(imu_.init_gyro_bias_sigma_rad_s, 2);
  P.block<3, 3>(kBa, kBa) = Mat3::Identity() * sba * sba;
  P.block<3, 3>(kGrav, kGrav) = P_g;

  samples_.clear();
  samples_.shrink_to_fit();
  start_utime_ = frame.utime;
  std::ostringstream os;
  os.precision(3);
  os << "filter started at once from " << use << " IMU samples: gravity direction sigma "
     << std::atan2(std::sqrt(var_h), g) * 180.0 / M_PI << " deg (motion and vibration beyond the white noise "
     << std::sqrt(var_excess) << " m/s^2, horizontal acceleration " << std::sqrt(accel_h2) << " m/s^2"
     << (var_h < var_h_uncapped ? ", capped at imu.init_max_tilt_deg" : "") << "), velocity 0 with sigma " << sv
     << " m/s (imu.init_max_speed_mps / 2), accelerometer in " << (accel_scale > 1.5 ? "g" : "m/s^2")
     << "; the LiDAR updates observe the rest";
  prior_message_ = os.str();
  return true;
}

std::vector<Vec3> FilterStart::constrainedMapDirections() const {
  Mat3 H = Mat3::Zero();
  map_->forEachPlane([&H](const VoxelKey&, const Plane& pl) {
    if (pl.is_plane) H += double(pl.num_points) * pl.normal * pl.normal.transpose();
  });
  return constrainedDirections(H, H.trace(), kConstrainedShare);
}

double FilterStart::constrainedVelocitySigma(const StateCov& P, const std::vector<Vec3>& normals) {
  Mat3 M = Mat3::Zero();
  for (const Vec3& n : normals) M += n * n.transpose();
  const std::vector<Vec3> dirs = constrainedDirections(M, double(normals.size()), kConstrainedShare);
  if (dirs.empty()) return std::numeric_limits<double>::infinity();
  const Mat3 Pvv = P.block<3, 3>(sidx::kVel, sidx::kVel);
  double worst = 0.0;
  for (const Vec3& d : dirs) worst = std::max(worst, d.dot(Pvv * d));
  return std::sqrt(worst);
}

Vec3 FilterStart::searchPosition(const NavState& x, const std::vector<BodyPoint>& pts, double radius) const {
  if (occupancy_.empty() || pts.empty() || !(radius > 2.0 * occupancy_.cellSize(0))) return x.p_world_imu;
  std::vector<Vec3> q;  // at most 512 points, spread over the sweep: the cost is points x candidates
  const double stride = std::max(1.0, double(pts.size()) / 512.0);
  for (double i = 0; i < double(pts.size()); i += stride) q.push_back(x.R_world_imu * pts[std::size_t(i)].p_imu);
  const Vec3 offset = occupancy_.search(q, x.p_world_imu, radius).t - x.p_world_imu;
  // Within two fine cells the search is no better than the prediction; along a direction the map's
  // planes leave free (a corridor's axis) its best is the scan pattern's noise.
  if (offset.norm() <= 2.0 * occupancy_.cellSize(0)) return x.p_world_imu;
  Vec3 along = Vec3::Zero();
  for (const Vec3& d : constrainedMapDirections()) along += d * d.dot(offset);
  return x.p_world_imu + along;
}

void FilterStart::insert(const std::vector<BodyPoint>& pts, const NavState& x, const StateCov& P) {
  std::vector<PointWithCov> world;
  world.reserve(pts.size());
  const WorldPointCovariance point_cov(x, P);
  for (const auto& bp : pts) {
    const Vec3 q = x.R_world_imu * bp.p_imu;
    world.push_back({q + x.p_world_imu, point_cov(bp, q)});
    occupancy_.insert(q + x.p_world_imu);
  }
  map_->insert(world);
}

FilterStart::Step FilterStart::update(NavState& x, StateCov& P, const LidarScan& sweep,
                                      std::vector<ImuTracePoint>& trace, std::vector<BodyPoint>& points,
                                      WorkerPool* pool) {
  Step st;
  ++frames_;
  const double tol = lio_.range_noise_m;
  const double T = sweepSeconds(trace);
  const double sv_prior =
      std::sqrt(Eigen::SelfAdjointEigenSolver<Mat3>(P.block<3, 3>(sidx::kVel, sidx::kVel)).eigenvalues().maxCoeff());
  if (points.empty()) return st;
  if (map_->numRootVoxels() == 0) {  // the first scan: the start map's origin
    insert(points, x, StateCov::Zero());
    map_smear_m_ = sv_prior * T;
    registered_since_reseed_ = 0;
    return st;
  }
  const NavState x_prop = x;
  const StateCov P_prop = P;
  const double dt = sweepSeconds(trace);
  const double sp =
      std::sqrt(Eigen::SelfAdjointEigenSolver<Mat3>(P_prop.block<3, 3>(sidx::kPos, sidx::kPos)).eigenvalues().maxCoeff());
  Vec3 v_shift = Vec3::Zero();  // velocity change the trace was corrected by
  LioUpdateResult u;
  for (int round = 0; round < 4; ++round) {
    x = x_prop;
    P = P_prop;
    st.rounds = round + 1;
    NavState lin = x_prop;
    // Predicted position uncertain beyond half a voxel: the basin of point-to-plane is about a voxel.
    if (3.0 * sp > 0.5 * map_cfg_.voxel_size_m)
      lin.p_world_imu = searchPosition(x_prop, points, std::min(3.0 * sp, cfg_.max_speed_mps * std::max(dt, 0.01)));
    u = lidarUpdate(x, P, points, *map_, lio_, pool, &lin);
    if (u.matched < min_matches_) break;
    // The sweep was undistorted with the prior's velocity: again with the posterior's when they differ
    // by more than a return's noise over the sweep.
    const Vec3 dv = x.v_world - (x_prop.v_world + v_shift);
    if (dv.norm() * T <= 0.5 * tol || round == 3) break;
    v_shift += dv;
    const Utime t_end = trace.back().utime;
    for (auto& tp : trace) {
      tp.p_world_imu -= dv * toSeconds(t_end - tp.utime);
      tp.v_world += dv;
    }
    points = prepareScan(sweep, trace, T_imu_lidar_, lio_);
    if (points.empty()) break;
  }
  st.matched = u.matched;
  st.iterations = u.iterations;
  st.rms_residual_m = u.rms_residual_m;
  st.sigma_min = degeneracySigmaMin(u.matched_normals);
  last_matched_ = u.matched;
  if (u.matched < min_matches_) {
    x = x_prop;
    P = P_prop;
    // A young start map (a sparse LiDAR's first scan holds few planes) grows with the scan at the
    // prediction, its points carrying the pose's uncertainty; a map that holds planes where the scan
    // lies is kept as it is (the prediction, not the map, is wrong).
    int on_planes = 0;
    for (const auto& bp : points) {
      const Vec3 p = x.R_world_imu * bp.p_imu + x.p_world_imu;
      bool plane = false;
      map_->visitPlanes(map_->keyOf(p), [&plane](const Plane&) { plane = true; });
      on_planes += plane;
    }
    if (on_planes < min_matches_) {
      insert(points, x, P);
      map_smear_m_ = std::max(map_smear_m_, sv_prior * T);
    }
    return st;
  }
  st.registered = true;
  ++registered_;
  st.matched_index = u.matched_index;
  st.matched_normals = u.matched_normals;
  const double sigma_v = constrainedVelocitySigma(P, u.matched_normals);
  st.smear_m = sigma_v * T;
  // Observed: the smear is within a return's noise, or within three of them and no longer shrinking
  // (a noisy IMU's velocity stays that uncertain between frames: the running filter undistorts with
  // it too, so waiting longer would not sharpen the map).
  const bool settled = last_smear_m_ >= 0 && st.smear_m > 0.8 * last_smear_m_;
  const double bound = settled ? 3.0 * tol : tol;
  last_sigma_v_ = sigma_v;
  last_smear_m_ = st.smear_m;
  st.observed = map_smear_m_ <= bound && st.smear_m <= bound;
  if (st.observed) return st;
  if (map_smear_m_ > 2.0 * st.smear_m + tol) {  // this scan is a better start map than the map
    map_->clear();
    occupancy_.clear();
    insert(points, x, StateCov::Zero());
    map_smear_m_ = st.smear_m;
  } else {
    insert(points, x, StateCov::Zero());
    map_smear_m_ = std::max(map_smear_m_, st.smear_m);
  }
  return st;
}

std::string FilterStart::status() const {
  std::ostringstream os;
  os.precision(3);
  os << "starting: " << registered_ << " of " << frames_ << " frames registered";
  if (last_matched_ >= 0 && last_matched_ < min_matches_)
    os << " (last: " << last_matched_ << " points matched a plane, " << min_matches_ << " needed)";
  if (last_sigma_v_ >= 0)
    os << "; velocity sigma " << last_sigma_v_ << " m/s where the LiDAR sees, smear " << last_smear_m_ * 100
       << " cm (start map " << map_smear_m_ * 100 << " cm) against the range noise " << lio_.range_noise_m * 100 << " cm";
  return os.str();
}

}  // namespace livo
