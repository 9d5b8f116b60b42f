#include "livo/loop/pose_graph.hpp"

#include <ceres/ceres.h>

#include <cmath>
#include <memory>
#include <stdexcept>

namespace livo {

void PoseGraphConfig::load(const ConfigNode& loop) {
  loop.get("odometry_sigma_fraction", odometry_sigma_fraction).get("odometry_sigma_deg_per_m", odometry_sigma_deg_per_m);
  loop.get("loop_sigma_m", loop_sigma_m).get("loop_sigma_deg", loop_sigma_deg);
  loop.get("loop_robust_sigmas", loop_robust_sigmas).get("graph_iterations", max_iterations);
  auto positive = [&](double v, const char* key) { loop.check(std::isfinite(v) && v > 0, key, "must be > 0"); };
  positive(odometry_sigma_fraction, "odometry_sigma_fraction");
  positive(odometry_sigma_deg_per_m, "odometry_sigma_deg_per_m");
  positive(loop_sigma_m, "loop_sigma_m");
  positive(loop_sigma_deg, "loop_sigma_deg");
  loop.check(std::isfinite(loop_robust_sigmas) && loop_robust_sigmas >= 0, "loop_robust_sigmas", "must be >= 0");
  loop.check(max_iterations >= 1 && max_iterations <= 10000, "graph_iterations", "must be in [1, 10000]");
}

namespace {

// Error of a relative-pose measurement Z = (q_z, t_z) of node b in node a:
//   e_rot = 2 vec(q_z^-1 q_a^-1 q_b)  (the rotation vector for small errors),
//   e_pos = q_a^-1 (t_b - t_a) - t_z,
// whitened by diagonal sigmas (rotation rad, position m).
struct RelativePoseError {
  Eigen::Quaterniond q_z;
  Vec3 t_z;
  double inv_rot, inv_pos;

  template <class T>
  bool operator()(const T* qa_p, const T* ta_p, const T* qb_p, const T* tb_p, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> qa(qa_p), qb(qb_p);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> ta(ta_p), tb(tb_p);
    const Eigen::Quaternion<T> q_ab = qa.conjugate() * qb;
    const Eigen::Matrix<T, 3, 1> t_ab = qa.conjugate() * (tb - ta);
    const Eigen::Quaternion<T> dq = q_z.cast<T>().conjugate() * q_ab;
    const Eigen::Matrix<T, 3, 1> e_rot = T(2.0) * dq.vec() * (dq.w() < T(0) ? T(-1) : T(1));
    const Eigen::Matrix<T, 3, 1> e_pos = t_ab - t_z.cast<T>();
    for (int i = 0; i < 3; ++i) {
      r[i] = e_rot[i] * T(inv_rot);
      r[3 + i] = e_pos[i] * T(inv_pos);
    }
    return true;
  }
};

}  // namespace

int PoseGraph::addKeyframe(const Pose& T_odom_key) {
  if (!odom_.empty()) {
    PoseGraphEdge e;
    e.from = static_cast<int>(odom_.size()) - 1;
    e.to = e.from + 1;
    e.T_from_to = odom_.back().inverse() * T_odom_key;
    edges_.push_back(e);
  }
  odom_.push_back(T_odom_key);
  map_.push_back(correction_ * T_odom_key);
  return static_cast<int>(odom_.size()) - 1;
}

void PoseGraph::addLoop(int from, int to, const Pose& T_from_to) {
  const int n = static_cast<int>(odom_.size());
  if (from < 0 || to < 0 || from >= n || to >= n || from == to)
    throw std::invalid_argument("PoseGraph::addLoop: keyframes " + std::to_string(from) + " and " + std::to_string(to) +
                                " (graph of " + std::to_string(n) + ")");
  edges_.push_back({from, to, T_from_to, true});
  ++loops_;
}

PoseGraphReport PoseGraph::optimize() {
  PoseGraphReport rep;
  if (odom_.size() < 2 || loops_ == 0) {
    rep.solved = true;
    return rep;  // nothing to correct: the map frame is the odometry's
  }
  const std::size_t n = map_.size();
  std::vector<Eigen::Quaterniond> q(n);
  std::vector<Vec3> t(n);
  for (std::size_t i = 0; i < n; ++i) {
    q[i] = Eigen::Quaterniond(map_[i].linear()).normalized();
    t[i] = map_[i].translation();
  }
  ceres::Problem::Options popt;
  popt.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  popt.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  ceres::EigenQuaternionManifold quaternion;
  // The loops' Cauchy scale narrows over the solves (graduated non-convexity): a true loop after a long
  // drift starts hundreds of sigmas off, where a narrow Cauchy loss would hardly weigh it and the solve
  // would stay at the odometry; a wide loss first pulls the graph towards what the loops agree on, the
  // narrow one then discounts a loop the others contradict.
  std::vector<double> scales;
  if (cfg_.loop_robust_sigmas > 0)
    for (double sc = 1000.0; sc > cfg_.loop_robust_sigmas; sc /= 4.0) scales.push_back(sc);
  scales.push_back(cfg_.loop_robust_sigmas);
  std::vector<std::unique_ptr<ceres::LossFunctionWrapper>> losses;
  for (const PoseGraphEdge& e : edges_) {
    RelativePoseError err;
    err.q_z = Eigen::Quaterniond(e.T_from_to.linear()).normalized();
    err.t_z = e.T_from_to.translation();
    ceres::LossFunction* loss = nullptr;
    if (e.loop) {
      err.inv_rot = 1.0 / (cfg_.loop_sigma_deg * M_PI / 180.0);
      err.inv_pos = 1.0 / cfg_.loop_sigma_m;
      if (cfg_.loop_robust_sigmas > 0) {
        losses.push_back(std::make_unique<ceres::LossFunctionWrapper>(new ceres::CauchyLoss(scales[0]),
                                                                      ceres::TAKE_OWNERSHIP));
        loss = losses.back().get();
      }
    } else {
      const double len = e.T_from_to.translation().norm();
      err.inv_rot = 1.0 / cfg_.odometrySigmaRad(len);
      err.inv_pos = 1.0 / cfg_.odometrySigmaM(len);
    }
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseError, 6, 4, 3, 4, 3>(new RelativePoseError(err));
    const auto a = static_cast<std::size_t>(e.from), b = static_cast<std::size_t>(e.to);
    problem.AddResidualBlock(cost, loss, q[a].coeffs().data(), t[a].data(), q[b].coeffs().data(), t[b].data());
  }
  for (std::size_t i = 0; i < n; ++i)
    if (problem.HasParameterBlock(q[i].coeffs().data())) problem.SetManifold(q[i].coeffs().data(), &quaternion);
  problem.SetParameterBlockConstant(q[0].coeffs().data());
  problem.SetParameterBlockConstant(t[0].data());

  ceres::Solver::Options opt;
  opt.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  opt.max_num_iterations = cfg_.max_iterations;
  opt.num_threads = 1;
  opt.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  for (std::size_t k = 0; k < scales.size(); ++k) {
    for (auto& l : losses) l->Reset(new ceres::CauchyLoss(scales[k]), ceres::TAKE_OWNERSHIP);
    ceres::Solve(opt, &problem, &summary);
    rep.iterations += static_cast<int>(summary.iterations.size());
    if (!summary.IsSolutionUsable()) break;
  }
  rep.solved = summary.IsSolutionUsable();
  if (!rep.solved) {
    rep.message = summary.BriefReport();
    return rep;  // the poses stay as they were
  }
  for (std::size_t i = 0; i < n; ++i) {
    Pose P = Pose::Identity();
    P.linear() = q[i].normalized().toRotationMatrix();
    P.translation() = t[i];
    map_[i] = P;
  }
  correction_ = map_.back() * odom_.back().inverse();
  return rep;
}

}  // namespace livo
