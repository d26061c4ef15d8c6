#pragma once
// The residual of the mount estimate (core/MountEstimation): one matched pair of camera rays, seen from a
// reference frame and the current one, each cast onto the ground with its frame's roll, pitch and height;
// the current point moved by the robot's motion (x, y, theta) should land on the reference point.
// Derivatives are analytic: the estimate runs every frame, and automatic differentiation of the two
// rotations per pair cost more than the rest of the solve.
#include <Eigen/Core>
#include <ceres/sized_cost_function.h>

namespace groundslam {

/// Where a ray (robot frame, already turned by the calibrated mount's rotation) meets the ground when turned by
/// pitch then roll and cast from an optical centre at `height` above `centre_xy`; optionally its Jacobian with
/// respect to (roll, pitch, height).
Eigen::Vector2d mountGroundPoint(const Eigen::Vector3d& ray_robot, const Eigen::Vector2d& centre_xy, const double* state,
                                 Eigen::Matrix<double, 2, 3>* jacobian);

/// Residual (2) over the reference state (roll, pitch, height), the current state and the motion, in units
/// of the point noise `sigma`.
class MountPairCost : public ceres::SizedCostFunction<2, 3, 3, 3> {
 public:
  MountPairCost(const Eigen::Vector3d& reference_ray, const Eigen::Vector3d& current_ray, const Eigen::Vector2d& centre_xy,
                double sigma);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d reference_ray_, current_ray_;
  Eigen::Vector2d centre_xy_;
  double inverse_sigma_;
};

}  // namespace groundslam
