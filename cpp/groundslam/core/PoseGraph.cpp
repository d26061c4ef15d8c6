#include "groundslam/core/PoseGraph.hpp"

#include <algorithm>
#include <array>
#include <unordered_map>
#include <cmath>

#include <Eigen/Cholesky>
#include <ceres/ceres.h>

namespace groundslam {
namespace {

template <typename T>
T normaliseAngle(const T& angle) {
  const T two_pi(2.0 * M_PI);
  return angle - two_pi * ceres::floor((angle + T(M_PI)) / two_pi);
}

/// Residual of one edge (Ceres' pose_graph_2d form):
///   r = sqrt(I) [ R(theta_a)^T (p_b - p_a) - p_ab ;  wrap(theta_b - theta_a - theta_ab) ].
struct EdgeResidual {
  EdgeResidual(const Pose2& T_a_b, const Eigen::Matrix3d& sqrt_information)
      : T_a_b_(T_a_b), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    const T c = ceres::cos(a[2]), s = ceres::sin(a[2]);
    const T dx = b[0] - a[0], dy = b[1] - a[1];
    const Eigen::Matrix<T, 3, 1> error(c * dx + s * dy - T(T_a_b_.x), -s * dx + c * dy - T(T_a_b_.y),
                                       normaliseAngle(b[2] - a[2] - T(T_a_b_.theta)));
    Eigen::Map<Eigen::Matrix<T, 3, 1>> whitened(residual);
    whitened = sqrt_information_.cast<T>() * error;
    return true;
  }

  Pose2 T_a_b_;
  Eigen::Matrix3d sqrt_information_;
};

/// The later of an edge's two poses: an edge touches the window [first_free, ...) when this lies in it.
int lastPoseOf(const GraphEdge& edge) { return std::max(edge.from, edge.to); }

}  // namespace

Eigen::Matrix3d sigmaCovariance(double sigma_m, double sigma_rad) {
  return Eigen::Vector3d(sigma_m * sigma_m, sigma_m * sigma_m, sigma_rad * sigma_rad).asDiagonal();
}

Eigen::Matrix3d informationFrom(const Eigen::Matrix3d& covariance, double min_sigma_m, double min_sigma_rad) {
  const Eigen::Matrix3d floored =
      covariance + Eigen::Vector3d(min_sigma_m * min_sigma_m, min_sigma_m * min_sigma_m, min_sigma_rad * min_sigma_rad)
                       .asDiagonal()
                       .toDenseMatrix();
  return floored.inverse();
}

PoseGraph::PoseGraph(const PoseGraphSettings& settings) : settings_(settings) {}

int PoseGraph::addPose(const Pose2& initial_T_world_robot) {
  poses_.push_back(initial_T_world_robot);
  return static_cast<int>(poses_.size()) - 1;
}

void PoseGraph::addEdge(const GraphEdge& edge) {
  if (!edges_.empty() && lastPoseOf(edge) < lastPoseOf(edges_.back())) edges_in_pose_order_ = false;
  edges_.push_back(edge);
}

OptimisationSummary PoseGraph::optimise(int first_free) {
  OptimisationSummary result;
  first_free = std::max(first_free, 0);
  if (poses_.size() < 2 || first_free >= static_cast<int>(poses_.size())) return result;
  // Edges touching the window: with edges in pose order they are a suffix of edges_.
  auto first_edge = edges_.begin();
  if (edges_in_pose_order_) {
    first_edge = std::partition_point(edges_.begin(), edges_.end(), [&](const GraphEdge& e) { return lastPoseOf(e) < first_free; });
  }
  // Parameter blocks: the window's poses, and the fixed poses outside it that its edges reach.
  std::unordered_map<int, std::array<double, 3>> parameters;
  const auto block = [&](int pose) {
    auto [it, added] = parameters.try_emplace(pose);
    if (added) {
      const Pose2& p = poses_[static_cast<size_t>(pose)];
      it->second = {p.x, p.y, p.theta};
    }
    return it->second.data();
  };
  ceres::Problem problem;
  for (auto edge = first_edge; edge != edges_.end(); ++edge) {
    if (lastPoseOf(*edge) < first_free) continue;
    // The upper Cholesky factor U of the information (I = U^T U) whitens the error.
    const Eigen::Matrix3d sqrt_information = edge->information.llt().matrixU();
    auto* cost = new ceres::AutoDiffCostFunction<EdgeResidual, 3, 3, 3>(new EdgeResidual(edge->T_from_to, sqrt_information));
    ceres::LossFunction* loss = edge->loop ? new ceres::CauchyLoss(settings_.loop_loss_scale) : nullptr;
    problem.AddResidualBlock(cost, loss, block(edge->from), block(edge->to));
  }
  // The map frame is the first pose: without fixing it the solution could slide freely (gauge freedom).
  // Poses before the window are held where they are.
  for (auto& [pose, values] : parameters) {
    if (pose == 0 || pose < first_free) problem.SetParameterBlockConstant(values.data());
  }
  if (problem.NumResidualBlocks() == 0) return result;
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.max_num_iterations = settings_.max_iterations;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  for (const auto& [pose, v] : parameters) {
    if (pose >= first_free) poses_[static_cast<size_t>(pose)] = Pose2(v[0], v[1], v[2]);
  }
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.iterations = static_cast<int>(summary.iterations.size());
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  return result;
}

}  // namespace groundslam
