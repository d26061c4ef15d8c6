#include "groundslam/core/MountEstimation.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <ceres/ceres.h>

#include "groundslam/core/MountPairCost.hpp"
#include "groundslam/core/NormalCovariance.hpp"

namespace groundslam {
namespace {

/// A Gaussian prior on the first `N` parameters of a block.
template <int N>
struct Prior {
  Prior(const Eigen::Matrix<double, N, 1>& mean, const Eigen::Matrix<double, N, 1>& sigma) : mean_(mean), sigma_(sigma) {}
  template <typename T>
  bool operator()(const T* value, T* residual) const {
    for (int i = 0; i < N; ++i) residual[i] = (value[i] - mean_(i)) / sigma_(i);
    return true;
  }
  Eigen::Matrix<double, N, 1> mean_, sigma_;
};

Eigen::Matrix3d roll_pitch(double roll, double pitch) {
  return (Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY())).toRotationMatrix();
}

}  // namespace

Eigen::Isometry3d mountFor(const Eigen::Isometry3d& calibrated, const MountState& state) {
  Eigen::Isometry3d T = calibrated;
  T.linear() = roll_pitch(state.roll_rad, state.pitch_rad) * calibrated.linear();
  T.translation().z() = state.height_m;
  return T;
}

MountState calibratedState(const Eigen::Isometry3d& calibrated) { return {0.0, 0.0, calibrated.translation().z()}; }

MountEstimate estimateMount(const std::vector<Eigen::Vector2d>& reference_rays, const std::vector<Eigen::Vector2d>& current_rays,
                            const Eigen::Isometry3d& calibrated, const MountState& reference, const Pose2& T_guess,
                            const MountEstimationSettings& settings) {
  return estimateMount({MountObservation{reference_rays, current_rays, reference, T_guess}}, calibrated, settings);
}

MountEstimate estimateMount(const std::vector<MountObservation>& observations, const Eigen::Isometry3d& calibrated,
                            const MountEstimationSettings& settings) {
  MountEstimate estimate;
  size_t total = 0;
  for (const MountObservation& o : observations) total += std::min(o.reference_rays.size(), o.current_rays.size());
  if (observations.empty() || total < static_cast<size_t>(std::max(3, settings.min_pairs))) return estimate;
  const Eigen::Matrix3d R0 = calibrated.linear();
  const Eigen::Vector2d centre_xy = calibrated.translation().head<2>();
  const MountState nominal = calibratedState(calibrated);
  const MountState& first = observations.front().reference;
  double current[3] = {first.roll_rad, first.pitch_rad, first.height_m};
  std::vector<std::array<double, 3>> reference_states(observations.size());
  std::vector<std::array<double, 3>> motions(observations.size());

  ceres::Problem problem;
  ceres::LossFunction* loss = new ceres::HuberLoss(3.0);  // shared by the pair residuals, owned by the problem
  for (size_t k = 0; k < observations.size(); ++k) {
    const MountObservation& o = observations[k];
    reference_states[k] = {o.reference.roll_rad, o.reference.pitch_rad, o.reference.height_m};
    motions[k] = {o.T_guess.x, o.T_guess.y, o.T_guess.theta};
    const size_t n = std::min(o.reference_rays.size(), o.current_rays.size());
    const size_t step = std::max<size_t>(1, n / static_cast<size_t>(std::max(1, settings.max_pairs)));
    for (size_t i = 0; i < n; i += step) {
      const Eigen::Vector3d ref = R0 * Eigen::Vector3d(o.reference_rays[i].x(), o.reference_rays[i].y(), 1.0);
      const Eigen::Vector3d cur = R0 * Eigen::Vector3d(o.current_rays[i].x(), o.current_rays[i].y(), 1.0);
      problem.AddResidualBlock(new MountPairCost(ref, cur, centre_xy, settings.point_sigma_m), loss,
                               reference_states[k].data(), current, motions[k].data());
      ++estimate.pairs;
    }
    if (n == 0) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Prior<2>, 2, 3>(new Prior<2>(
                                 Eigen::Vector2d(o.reference.roll_rad, o.reference.pitch_rad),
                                 Eigen::Vector2d::Constant(settings.reference_sigma_rad))),
                             nullptr, reference_states[k].data());
    // The reference's height is held: it fixes the scale.
    problem.SetManifold(reference_states[k].data(), new ceres::SubsetManifold(3, {2}));
  }
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Prior<3>, 3, 3>(new Prior<3>(
                               Eigen::Vector3d(nominal.roll_rad, nominal.pitch_rad, nominal.height_m),
                               Eigen::Vector3d(settings.tilt_prior_rad, settings.tilt_prior_rad, settings.height_prior_m))),
                           nullptr, current);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;  // a dozen parameters: the normal equations are tiny
  options.max_num_iterations = 20;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable() || !std::isfinite(current[0] + current[1] + current[2]) || current[2] <= 0.0) return estimate;
  // The covariance of the current state (tangent space: 3 columns for it, 2 per reference, 3 per motion).
  std::vector<double*> blocks = {current};
  for (size_t k = 0; k < observations.size(); ++k) {  // an observation without pairs added no blocks
    if (problem.HasParameterBlock(reference_states[k].data())) blocks.push_back(reference_states[k].data());
    if (problem.HasParameterBlock(motions[k].data())) blocks.push_back(motions[k].data());
  }
  const std::optional<Eigen::MatrixXd> full_covariance = normalCovariance(problem, blocks);
  if (!full_covariance) return estimate;
  const Eigen::Matrix3d state_covariance = full_covariance->topLeftCorner<3, 3>();
  // Ceres assumes the residuals have unit variance; scale by their observed variance.
  const double dof = std::max(1.0, 2.0 * estimate.pairs - static_cast<double>(problem.NumParameters()));
  const double residual_variance = std::max(1.0, 2.0 * summary.final_cost / dof);
  estimate.tilt_covariance = state_covariance.topLeftCorner<2, 2>() * residual_variance;
  estimate.height_variance = state_covariance(2, 2) * residual_variance;
  estimate.ok = true;
  estimate.current = {current[0], current[1], current[2]};
  estimate.reference = {reference_states[0][0], reference_states[0][1], reference_states[0][2]};
  estimate.T_reference_current = Pose2(motions[0][0], motions[0][1], motions[0][2]);
  return estimate;
}

}  // namespace groundslam
