#pragma once
// The covariance of a least-squares solution from its normal equations: the inverse of J^T J, with J the
// (robustified) Jacobian at the solution. For the small problems of this project (3 to a dozen parameters, a few
// hundred residuals) it costs a fraction of ceres::Covariance's dense SVD and gives the same matrix when J has
// full rank.
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <ceres/problem.h>

namespace groundslam {

/// Covariance over the tangent spaces of `blocks`, in that order (rows and columns of block 0 first). Empty
/// when J^T J is not positive definite (a parameter the residuals do not fix) or the Jacobian cannot be evaluated.
std::optional<Eigen::MatrixXd> normalCovariance(ceres::Problem& problem, const std::vector<double*>& blocks);

}  // namespace groundslam
