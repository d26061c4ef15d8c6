#include "groundslam/core/NormalCovariance.hpp"

#include <Eigen/Cholesky>
#include <ceres/crs_matrix.h>

namespace groundslam {

std::optional<Eigen::MatrixXd> normalCovariance(ceres::Problem& problem, const std::vector<double*>& blocks) {
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = blocks;
  options.apply_loss_function = true;
  ceres::CRSMatrix jacobian;
  if (!problem.Evaluate(options, nullptr, nullptr, nullptr, &jacobian)) return std::nullopt;
  const auto at = [](const auto& v, int i) { return v[static_cast<size_t>(i)]; };
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(jacobian.num_cols, jacobian.num_cols);
  for (int row = 0; row < jacobian.num_rows; ++row) {
    for (int a = at(jacobian.rows, row); a < at(jacobian.rows, row + 1); ++a) {
      for (int b = at(jacobian.rows, row); b < at(jacobian.rows, row + 1); ++b) {
        information(at(jacobian.cols, a), at(jacobian.cols, b)) += at(jacobian.values, a) * at(jacobian.values, b);
      }
    }
  }
  const Eigen::LLT<Eigen::MatrixXd> cholesky(information);
  if (cholesky.info() != Eigen::Success) return std::nullopt;
  Eigen::MatrixXd covariance = cholesky.solve(Eigen::MatrixXd::Identity(jacobian.num_cols, jacobian.num_cols));
  if (!covariance.allFinite()) return std::nullopt;
  return covariance;
}

}  // namespace groundslam
