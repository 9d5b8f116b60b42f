#include "livo/estimation/motion_init.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace livo {

void MotionInitConfig::load(const ConfigNode& n) {
  n.get("init_motion_rot_sigma_deg", rot_sigma_deg).get("init_motion_pos_sigma_m", pos_sigma_m);
  n.get("init_motion_min_updates", min_updates).get("init_motion_max_speed_sigma_mps", max_speed_sigma_mps);
  n.get("init_motion_max_tilt_sigma_deg", max_tilt_sigma_deg).get("init_motion_max_window_s", max_window_s);
  n.get("init_motion_max_speed_mps", max_speed_mps);
  n.check(rot_sigma_deg > 0 && rot_sigma_deg < 90, "init_motion_rot_sigma_deg", "must be in (0, 90) deg");
  n.check(pos_sigma_m > 0 && pos_sigma_m < 100, "init_motion_pos_sigma_m", "must be in (0, 100) m");
  n.check(min_updates >= 3 && min_updates <= 1000, "init_motion_min_updates", "must be in [3, 1000]");
  n.check(max_speed_sigma_mps > 0, "init_motion_max_speed_sigma_mps", "must be > 0");
  n.check(max_tilt_sigma_deg > 0 && max_tilt_sigma_deg < 30, "init_motion_max_tilt_sigma_deg", "must be in (0, 30) deg");
  n.check(max_window_s >= 1 && max_window_s <= 120, "init_motion_max_window_s", "must be in [1, 120] s");
  n.check(max_speed_mps >= 0 && max_speed_mps <= 100, "init_motion_max_speed_mps", "must be in [0, 100] m/s");
}

namespace {

ScanRegistrationConfig startRegistration(const LioConfig& lio, const VoxelMapConfig& map, int min_matches) {
  ScanRegistrationConfig c = ScanRegistrationConfig::from(lio, map, min_matches);
  // The first fixes register against a map of one or two scans, whose planes cover a share of the next
  // scan's points only (a sparse 5 Hz spinning LiDAR's second scan: 16 % of its points at the true pose).
  c.min_inlier_share = 0.1;
  return c;
}

}  // namespace

MotionInitializer::MotionInitializer(const ImuConfig& imu, MotionInitConfig cfg, VoxelMapConfig map, LioConfig lio,
                                     int min_matches, const Pose& T_imu_lidar)
    : imu_(imu), cfg_(cfg), lio_(lio), min_matches_(min_matches), T_imu_lidar_(T_imu_lidar),
      map_(std::make_unique<VoxelMap>(map)), first_map_(std::make_unique<VoxelMap>(map)),
      registration_(startRegistration(lio, map, min_matches)), search_(registration_.config()) {}

namespace {

double fixSigma(const LioConfig& lio) { return std::max(2.0 * lio.range_noise_m, 0.01); }

/// Trace over [t_from, t_to] with gyro rotation from R_from and constant velocity v from p_from.
std::vector<ImuTracePoint> gyroTrace(const std::vector<ImuSample>& samples, Utime t_from, Utime t_to, const Mat3& R_from,
                                     const Vec3& p_from, const Vec3& v) {
  std::vector<ImuTracePoint> trace;
  std::vector<Utime> cuts{t_from};
  for (const auto& s : samples)
    if (s.utime > cuts.back() && s.utime < t_to) cuts.push_back(s.utime);
  cuts.push_back(t_to);
  Mat3 R = R_from;
  std::size_t k = 0;
  for (std::size_t j = 0; j + 1 < cuts.size(); ++j) {
    while (k + 1 < samples.size() && samples[k + 1].utime <= cuts[j]) ++k;
    const ImuSample& a = samples[k];
    const ImuSample& b = (k + 1 < samples.size() && a.utime <= cuts[j]) ? samples[k + 1] : a;
    ImuTracePoint tp;
    tp.utime = cuts[j];
    tp.R_world_imu = R;
    tp.p_world_imu = p_from + v * toSeconds(cuts[j] - t_from);
    tp.v_world = v;
    tp.omega = 0.5 * (a.gyro + b.gyro);
    trace.push_back(tp);
    R = R * expSO3(tp.omega * toSeconds(cuts[j + 1] - cuts[j]));
  }
  ImuTracePoint end = trace.empty() ? ImuTracePoint{} : trace.back();
  end.utime = t_to;
  end.R_world_imu = R;
  end.p_world_imu = p_from + v * toSeconds(t_to - t_from);
  trace.push_back(end);
  return trace;
}

}  // namespace

bool MotionInitializer::start(const Frame& frame) {
  if (frame.imu.empty() || frame.sweep.points.empty()) return false;
  Vec3 mean = Vec3::Zero();
  for (const auto& s : frame.imu) mean += s.accel;
  mean /= double(frame.imu.size());
  const double norm = mean.norm();
  if (!(norm > 1e-3) || !std::isfinite(norm)) return false;  // no usable specific force yet
  accel_scale_ = norm < 4.0 ? imu_.gravity_m_s2 : 1.0;     // g units or m/s^2
  map_->clear();
  search_.clear();
  fixes_.clear();
  samples_ = frame.imu;
  v_cv_ = Vec3::Zero();
  solved_ = rebuilt_ = false;
  check_ = Check{};
  first_sweep_ = frame.sweep;
  first_frame_imu_.imu = frame.imu;
  first_frame_imu_.utime = frame.utime;
  // The first fix defines the world: the IMU frame at this frame's time.
  std::vector<ImuTracePoint> trace = gyroTrace(frame.imu, frame.imu.front().utime, frame.utime, Mat3::Identity(),
                                               Vec3::Zero(), Vec3::Zero());
  const Mat3 R_end_T = trace.back().R_world_imu.transpose();
  for (auto& tp : trace) tp.R_world_imu = R_end_T * tp.R_world_imu;
  points_ = prepare(frame.sweep, trace);
  if (points_.empty()) return false;
  insert(points_, Mat3::Identity(), Vec3::Zero());
  {
    std::vector<PointWithCov> world;
    world.reserve(points_.size());
    const WorldPointCovariance point_cov(NavState{}, StateCov::Zero());
    for (const auto& bp : points_) world.push_back({bp.p_imu, point_cov(bp, bp.p_imu)});
    first_map_->clear();
    first_map_->insert(world);
  }
  fixes_.push_back({frame.utime, Mat3::Identity(), Vec3::Zero()});
  started_ = true;
  last_utime_ = frame.utime;
  return true;
}

std::vector<ImuTracePoint> MotionInitializer::predictTrace(const Frame& frame, Mat3& R_pred, Vec3& p_pred) const {
  const Fix& last = fixes_.back();
  std::vector<ImuSample> s = frame.imu;
  if (!samples_.empty()) s.insert(s.begin(), samples_.back());  // the sample holding at the last fix
  std::vector<ImuTracePoint> trace = gyroTrace(s, last.utime, frame.utime, last.R, last.p, v_cv_);
  R_pred = trace.back().R_world_imu;
  p_pred = trace.back().p_world_imu;
  return trace;
}

bool MotionInitializer::registerFrame(const Mat3& R_pred, const Vec3& p_pred, Mat3& R, Vec3& p) const {
  NavState x;
  x.R_world_imu = R_pred;
  x.p_world_imu = p_pred;
  StateCov P = StateCov::Identity() * 1e-10;  // only the pose is free
  using namespace sidx;
  const double sr = cfg_.rot_sigma_deg * M_PI / 180.0;
  P.block<3, 3>(kRot, kRot) = Mat3::Identity() * sr * sr;
  P.block<3, 3>(kPos, kPos) = Mat3::Identity() * cfg_.pos_sigma_m * cfg_.pos_sigma_m;
  const LioUpdateResult u = lidarUpdate(x, P, points_, *map_, lio_);
  if (u.matched < min_matches_) return false;
  // A fix far beyond its prior slid along a direction the scan does not constrain.
  if ((x.p_world_imu - p_pred).norm() > 3.0 * cfg_.pos_sigma_m) return false;
  R = x.R_world_imu;
  p = x.p_world_imu;
  return true;
}

Mat3 MotionInitializer::normalScatter() const {
  Mat3 H = Mat3::Zero();
  map_->forEachPlane([&H](const VoxelKey&, const Plane& pl) {
    if (pl.is_plane) H += double(pl.num_points) * pl.normal * pl.normal.transpose();
  });
  return H;
}

double MotionInitializer::weakestShare() const {
  const Mat3 H = normalScatter();
  if (!(H.trace() > 0)) return 0.0;
  const double weakest = Eigen::SelfAdjointEigenSolver<Mat3>(H / H.trace(), Eigen::EigenvaluesOnly).eigenvalues()(0);
  return std::sqrt(std::max(0.0, weakest));
}

Vec3 MotionInitializer::searchPosition(const Mat3& R_pred, const Vec3& p_pred, double dt) const {
  const double radius = cfg_.max_speed_mps * dt;
  if (search_.empty() || points_.empty() || !(radius > 0.05)) return p_pred;
  // The scan registration (scan_registration.hpp): a correlative search within the speed limit, then a
  // robust coarse-to-fine point-to-plane refinement; along a direction the map leaves free (a wall, a
  // corridor's axis) it keeps the prediction. The rotation is the gyro's (a frame interval's drift
  // is far below the search's resolution).
  Pose T0 = Pose::Identity();
  T0.linear() = R_pred;
  T0.translation() = p_pred;
  SearchBounds bounds;
  bounds.translation_m = radius;
  const ScanRegistrationResult res = registration_.align(points_, *map_, search_, T0, bounds);
  if (!res.success) return p_pred;
  // Within two range noises the answer is no better than the prediction.
  const Vec3 t = res.T_world_body.translation();
  return (t - p_pred).norm() > 2.0 * lio_.range_noise_m ? t : p_pred;
}

void MotionInitializer::insert(const std::vector<BodyPoint>& pts, const Mat3& R, const Vec3& p) {
  NavState x;
  x.R_world_imu = R;
  x.p_world_imu = p;
  const StateCov P = StateCov::Zero();
  std::vector<PointWithCov> world;
  world.reserve(pts.size());
  const WorldPointCovariance point_cov(x, P);
  std::vector<Vec3> searched;
  for (const auto& bp : pts) {
    const Vec3 q = R * bp.p_imu;
    world.push_back({q + p, point_cov(bp, q)});
    if (fixes_.size() < 3) searched.push_back(q + p);  // the map the first fixes search
  }
  if (!searched.empty()) search_.addPoints(searched);
  map_->insert(world);
}

void MotionInitializer::rebuildMap(bool final) {
  // The first scan again, undistorted along the current velocity estimate.
  const Fix& f0 = fixes_.front();
  const Utime t_first = first_frame_imu_.imu.front().utime;
  std::vector<ImuTracePoint> trace =
      gyroTrace(first_frame_imu_.imu, t_first, f0.utime, Mat3::Identity(), Vec3::Zero(), v_cv_);
  const Mat3 R_end_T = trace.back().R_world_imu.transpose();
  const Vec3 p_end = trace.back().p_world_imu;
  for (auto& tp : trace) {
    tp.R_world_imu = R_end_T * tp.R_world_imu;
    tp.p_world_imu = R_end_T * (tp.p_world_imu - p_end);
  }
  map_->clear();
  search_.clear();
  insert(prepare(first_sweep_, trace), Mat3::Identity(), Vec3::Zero());
  if (final) {
    first_sweep_ = LidarScan{};
    rebuilt_ = true;
  }
}

const MotionInitializer::Fix* MotionInitializer::fixBefore(Utime t) const {
  // Velocities over shorter intervals are mostly registration noise (frames cut at image times may
  // be milliseconds apart).
  constexpr double kMinInterval = 0.05;
  for (auto it = fixes_.rbegin(); it != fixes_.rend(); ++it)
    if (toSeconds(t - it->utime) >= kMinInterval) return &*it;
  return nullptr;
}

bool MotionInitializer::process(const Frame& frame) {
  if (started_ && toSeconds(frame.utime - fixes_.front().utime) > cfg_.max_window_s) started_ = false;  // start over
  if (!started_) return start(frame) && false;
  if (frame.utime <= last_utime_) return solved_;
  last_utime_ = frame.utime;
  Mat3 R_pred, R;
  Vec3 p_pred, p;
  std::vector<ImuTracePoint> trace = predictTrace(frame, R_pred, p_pred);
  points_ = prepare(frame.sweep, trace);
  const Fix& last = fixes_.back();
  const double dt = std::max(1e-3, toSeconds(frame.utime - last.utime));
  if (fixes_.size() < 3 && !points_.empty()) {
    // The speed is not known yet: search, undistort along the velocity the search implies (before the
    // first fix, the map's first scan too, which was undistorted at rest), and search again until the
    // velocity settles: each round shrinks the smear's error by about scan length / (2 interval).
    for (int round = 0; round < 4; ++round) {
      const Vec3 v = (searchPosition(R_pred, p_pred, dt) - last.p) / dt;
      if (v == v_cv_) break;  // the search kept the prediction
      const bool settled = (v - v_cv_).norm() * dt < 0.05;
      v_cv_ = v;
      trace = predictTrace(frame, R_pred, p_pred);
      points_ = prepare(frame.sweep, trace);
      if (settled || fixes_.size() > 1) break;
      rebuildMap(false);
    }
  }
  std::vector<ImuTracePoint> rest_trace;
  {
    std::vector<ImuSample> held = frame.imu;
    if (!samples_.empty()) held.insert(held.begin(), samples_.back());
    rest_trace = gyroTrace(held, last.utime, frame.utime, last.R, Vec3::Zero(), Vec3::Zero());
  }
  samples_.insert(samples_.end(), frame.imu.begin(), frame.imu.end());
  if (fixes_.size() >= 3) search_.clear();
  if (points_.empty() || !registerFrame(R_pred, p_pred, R, p)) return solved_;
  Fix fix{frame.utime, R, p};
  {
    // The rest test's evidence: the scan undistorted at rest (gyro rotation, no translation) against
    // the first scan alone, at the first scan's position and at the fix.
    const std::vector<BodyPoint> at_rest = prepare(frame.sweep, rest_trace);
    fix.matches_at_origin = firstMapMatches(at_rest, R, Vec3::Zero(), p, &fix.shift_on_normals_m);
    fix.matches_at_fix = firstMapMatches(at_rest, R, p);
  }
  if (const Fix* base = fixBefore(frame.utime)) v_cv_ = (p - base->p) / toSeconds(frame.utime - base->utime);
  fixes_.push_back(fix);
  if (!rebuilt_ && fixes_.size() == 2) rebuildMap(true);
  else insert(points_, R, p);
  Solution s;
  solved_ = solve(s) && accept(s);
  if (solved_) solution_ = s;
  return solved_;
}

void MotionInitializer::integrate(Utime t, Mat3& R, Vec3& dv, Vec3& alpha) const {
  R = Mat3::Identity();
  dv = alpha = Vec3::Zero();
  const Utime t0 = fixes_.front().utime;
  for (std::size_t i = 0; i + 1 < samples_.size(); ++i) {
    const Utime a = std::max(samples_[i].utime, t0), b = std::min(samples_[i + 1].utime, t);
    if (b <= a) continue;
    const double dt = toSeconds(b - a);
    const Vec3 w = 0.5 * (samples_[i].gyro + samples_[i + 1].gyro);
    const Vec3 acc = R * (0.5 * (samples_[i].accel + samples_[i + 1].accel) * accel_scale_);
    alpha += dv * dt + 0.5 * acc * dt * dt;
    dv += acc * dt;
    R = R * expSO3(w * dt);
  }
}

bool MotionInitializer::solve(Solution& s) const {
  if (static_cast<int>(fixes_.size()) < cfg_.min_updates + 1) return false;
  // Rows p_k - alpha_k = [tau I, tau^2/2 I] [v0; g], k >= 1 (the first fix is the origin).
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  Mat6 N = Mat6::Zero();
  Vec6 rhs = Vec6::Zero();
  std::vector<std::pair<double, Vec3>> rows;
  for (std::size_t k = 1; k < fixes_.size(); ++k) {
    const double tau = toSeconds(fixes_[k].utime - fixes_.front().utime);
    Mat3 R;
    Vec3 dv, alpha;
    integrate(fixes_[k].utime, R, dv, alpha);
    Eigen::Matrix<double, 3, 6> A;
    A << Mat3::Identity() * tau, Mat3::Identity() * (0.5 * tau * tau);
    const Vec3 b = fixes_[k].p - alpha;
    N += A.transpose() * A;
    rhs += A.transpose() * b;
    rows.emplace_back(tau, b);
  }
  const Eigen::LDLT<Mat6> ldlt(N);
  if (ldlt.info() != Eigen::Success || ldlt.rcond() < 1e-12) return false;
  const Vec6 x = ldlt.solve(rhs);
  if (!x.allFinite() || x.tail<3>().norm() < 1.0) return false;
  // |g| known: fix it and solve v0 again.
  s.g = x.tail<3>().normalized() * imu_.gravity_m_s2;
  double tt = 0;
  Vec3 tv = Vec3::Zero();
  for (const auto& [tau, b] : rows) {
    tt += tau * tau;
    tv += tau * (b - 0.5 * tau * tau * s.g);
  }
  s.v0 = tv / tt;
  double sq = 0;
  for (const auto& [tau, b] : rows) sq += (b - s.v0 * tau - 0.5 * tau * tau * s.g).squaredNorm();
  s.rms = std::sqrt(sq / (3.0 * double(rows.size())));
  const double sp = fixSigma(lio_);
  s.cov = ldlt.solve(Mat6::Identity()) * sp * sp;
  return true;
}

bool MotionInitializer::accept(const Solution& s) {
  check_ = Check{true, s.rms, -1.0, -1.0};
  if (s.rms > 3.0 * fixSigma(lio_)) return false;  // the fixes do not fit one motion: registration failed
  const double tau = toSeconds(fixes_.back().utime - fixes_.front().utime);
  Eigen::Matrix<double, 3, 6> J;
  J << Mat3::Identity(), Mat3::Identity() * tau;  // v(tau) = v0 + g tau + dv
  const Mat3 cov_v = J * s.cov * J.transpose();
  const Vec3 gd = s.g.normalized();
  const Mat3 across = Mat3::Identity() - gd * gd.transpose();
  const Mat3 cov_g = across * s.cov.bottomRightCorner<3, 3>() * across;
  const double sigma_v = std::sqrt(Eigen::SelfAdjointEigenSolver<Mat3>(cov_v).eigenvalues().maxCoeff());
  const double sigma_tilt =
      std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat3>(cov_g).eigenvalues().maxCoeff())) / s.g.norm();
  check_.sigma_v = sigma_v;
  check_.sigma_tilt_deg = sigma_tilt * 180.0 / M_PI;
  return sigma_v < cfg_.max_speed_sigma_mps && sigma_tilt < cfg_.max_tilt_sigma_deg * M_PI / 180.0;
}

std::string MotionInitializer::status() const {
  std::ostringstream os;
  os.precision(3);
  os << "motion initialisation: " << (started_ ? fixes_.size() : 0) << " of " << cfg_.min_updates + 1 << " LiDAR fixes";
  if (!started_ || static_cast<int>(fixes_.size()) < cfg_.min_updates + 1 || !check_.done) return os.str();
  if (check_.sigma_v < 0)
    os << ", the fixes do not fit one motion (residual RMS " << check_.rms * 100 << " cm of " << 300 * fixSigma(lio_)
       << " allowed)";
  else
    os << ", velocity sigma " << check_.sigma_v << " m/s of " << cfg_.max_speed_sigma_mps << ", tilt sigma "
       << check_.sigma_tilt_deg << " deg of " << cfg_.max_tilt_sigma_deg;
  return os.str();
}

bool MotionInitializer::velocityBody(Vec3& v) const {
  // The velocities of the last two fix intervals (each at least 50 ms) must agree (within what
  // 5 m/s^2 changes over them, plus 0.2 m/s of fix noise): fixes in degenerate geometry (a single
  // wall, a corridor's axis) slide freely and give any velocity, and consistently so: the map's
  // planes must constrain every direction (weakestShare).
  if (!started_ || fixes_.empty() || weakestShare() < kConstrainedShare) return false;
  const Fix& c = fixes_.back();
  const Fix* b = fixBefore(c.utime);
  const Fix* a = b ? fixBefore(b->utime) : nullptr;
  if (!a) return false;
  const double dt1 = toSeconds(b->utime - a->utime), dt2 = toSeconds(c.utime - b->utime);
  const Vec3 v1 = (b->p - a->p) / dt1, v2 = (c.p - b->p) / dt2;
  if (!v1.allFinite() || !v2.allFinite() || (v2 - v1).norm() > 0.2 + 5.0 * (dt1 + dt2) || v2.norm() > 50.0) return false;
  v = c.R.transpose() * v2;
  return true;
}

void MotionInitializer::takeOver(NavState& x, StateCov& P) {
  const Fix& f = fixes_.back();
  const double tau = toSeconds(f.utime - fixes_.front().utime);
  Mat3 R_imu;
  Vec3 dv, alpha;
  integrate(f.utime, R_imu, dv, alpha);
  x = NavState();
  x.utime = f.utime;
  x.R_world_imu = f.R;
  x.p_world_imu = f.p;
  x.v_world = solution_.v0 + solution_.g * tau + dv;
  x.g_world = solution_.g;
  using namespace sidx;
  P = initialCovariance();
  P.block<3, 3>(kRot, kRot) = Mat3::Identity() * 1e-6;  // registered
  P.block<3, 3>(kPos, kPos) = Mat3::Identity() * 1e-6;
  Eigen::Matrix<double, 3, 6> J;
  J << Mat3::Identity(), Mat3::Identity() * tau;
  P.block<3, 3>(kVel, kVel) = J * solution_.cov * J.transpose();
  P.block<3, 3>(kGrav, kGrav) = solution_.cov.bottomRightCorner<3, 3>();
  P.block<3, 3>(kVel, kGrav) = J * solution_.cov.rightCols<3>();
  P.block<3, 3>(kGrav, kVel) = P.block<3, 3>(kVel, kGrav).transpose();
  P.block<3, 3>(kBg, kBg) = Mat3::Identity() * imu_.init_gyro_bias_sigma_rad_s * imu_.init_gyro_bias_sigma_rad_s;
  P.block<3, 3>(kBa, kBa) = Mat3::Identity() * imu_.init_accel_bias_sigma_mps2 * imu_.init_accel_bias_sigma_mps2;
  if (imu_.gravity_align) {
    // World rotated so that gravity points along -z: position, velocity and gravity rotate; the
    // rotation error is in the body frame.
    const Mat3 A = Quat::FromTwoVectors(x.g_world.normalized(), Vec3(0, 0, -1)).toRotationMatrix();
    x.R_world_imu = A * x.R_world_imu;
    x.p_world_imu = A * x.p_world_imu;
    x.v_world = A * x.v_world;
    x.g_world = A * x.g_world;
    StateCov T = StateCov::Identity();
    for (int b : {kPos, kVel, kGrav}) T.block<3, 3>(b, b) = A;
    P = T * P * T.transpose();
  }
  map_.reset();
}

int MotionInitializer::firstMapMatches(const std::vector<BodyPoint>& pts, const Mat3& R, const Vec3& p,
                                       const Vec3& shift, double* shift_rms_m) const {
  NavState x;
  x.R_world_imu = R;
  x.p_world_imu = p;
  const WorldPointCovariance point_cov(x, StateCov::Zero());
  int n = 0;
  double shift_sq = 0.0;
  for (const auto& bp : pts) {
    const Vec3 q = R * bp.p_imu;
    PlaneMatch m;
    if (!first_map_->findBestPlane({q + p, point_cov(bp, q)}, m)) continue;
    ++n;
    const double along = m.plane->normal.dot(shift);
    shift_sq += along * along;
  }
  if (shift_rms_m) *shift_rms_m = n > 0 ? std::sqrt(shift_sq / n) : 0.0;
  return n;
}

bool MotionInitializer::fixesFailedAtRest(Utime from) const {
  if (!check_.done || !(check_.rms > 3.0 * fixSigma(lio_))) return false;  // the fixes fit one motion
  // Summed over the fixes: a frame cut milliseconds after the last (at an image) holds few points.
  // Only fixes whose offset from the first scan's position the first scan's planes resolve (the offset
  // projected on the normals of the planes matched there, RMS, beyond the fixes' 3-sigma): a rig that
  // slides along a wall matches it as well at the origin as at its fix, which is no evidence of rest.
  const ResolvedMatches m = resolvedMatches(from);
  return m.fixes >= 2 && m.at_origin >= min_matches_ * m.fixes / 2 && 2 * m.at_origin >= m.at_fix;
}

MotionInitializer::ResolvedMatches MotionInitializer::resolvedMatches(Utime from) const {
  const double resolvable_m = 3.0 * fixSigma(lio_);
  ResolvedMatches m;
  for (const Fix& f : fixes_) {
    if (f.utime < from || f.matches_at_fix < 0 || !(f.shift_on_normals_m > resolvable_m)) continue;
    m.at_origin += f.matches_at_origin;
    m.at_fix += f.matches_at_fix;
    ++m.fixes;
  }
  return m;
}

Mat3 MotionInitializer::constrainedProjector() const {
  const Mat3 H = normalScatter();
  if (!(H.trace() > 0)) return Mat3::Identity();
  const Eigen::SelfAdjointEigenSolver<Mat3> es(H / H.trace());
  Mat3 P = Mat3::Zero();
  for (int k = 0; k < 3; ++k)
    if (std::sqrt(std::max(0.0, es.eigenvalues()(k))) >= kConstrainedShare)
      P += es.eigenvectors().col(k) * es.eigenvectors().col(k).transpose();
  return P;
}

bool MotionInitializer::atRestSince(Utime from, double tolerance_m, bool& known) const {
  // Along a direction the map's planes leave free (a wall's, a corridor's axis) the fixes slide
  // whatever the rig does: a spread there refutes rest only where the first scan resolves the
  // fixes' offsets and the scans match it at their fixes clearly better than at its own position.
  const Mat3 Pc = constrainedProjector();
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300), plo = lo, phi = hi;
  int n = 0;
  for (const Fix& f : fixes_) {
    if (f.utime < from) continue;
    lo = lo.cwiseMin(f.p);
    hi = hi.cwiseMax(f.p);
    plo = plo.cwiseMin(Pc * f.p);
    phi = phi.cwiseMax(Pc * f.p);
    ++n;
  }
  known = n >= 2;
  if (!known) return false;
  if ((hi - lo).norm() <= tolerance_m) return true;
  if ((phi - plo).norm() > tolerance_m) return fixesFailedAtRest(from);
  const ResolvedMatches m = resolvedMatches(from);
  const bool moved = m.fixes >= 2 && m.at_fix > 2 * m.at_origin;
  return !moved;
}

std::string MotionInitializer::describe() const {
  std::ostringstream os;
  const double tau = toSeconds(fixes_.back().utime - fixes_.front().utime);
  Mat3 R;
  Vec3 dv, alpha;
  integrate(fixes_.back().utime, R, dv, alpha);
  os << "IMU initialised in motion from " << fixes_.size() << " LiDAR fixes over " << tau
     << " s (gravity and velocity by least squares, residual RMS " << solution_.rms * 100 << " cm): speed "
     << (solution_.v0 + solution_.g * tau + dv).norm() << " m/s, accel scale " << accel_scale_;
  return os.str();
}

}  // namespace livo
