#pragma once
// The residual of the mount estimate (core/MountEstimation): one matched pair of camera rays, seen from a
// reference frame and the current one, each cast onto the ground with its frame's roll, pitch and height;
// the current point moved by the robot's motion (x, y, theta) should land on the reference point.
// Derivatives are analytic, and the sines and cosines of a state are computed once for all its pairs: the
// estimate runs every frame over a few hundred pairs.
#include <Eigen/Core>

namespace groundslam {

/// A state (roll, pitch, height) with the sines and cosines of its angles.
struct MountAngles {
  explicit MountAngles(const double* state);
  double cr, sr, cp, sp, height;
};

/// Where a ray (robot frame, already turned by the calibrated mount's rotation) meets the ground when turned by
/// pitch then roll and cast from an optical centre at `height` above `centre_xy`; optionally its Jacobian with
/// respect to (roll, pitch, height).
Eigen::Vector2d mountGroundPoint(const Eigen::Vector3d& ray_robot, const Eigen::Vector2d& centre_xy, const MountAngles& state,
                                 Eigen::Matrix<double, 2, 3>* jacobian);

/// One pair's residual (2), in units of the point noise: (R(theta) p_current + (x, y) - p_reference) / sigma.
class MountPairCost {
 public:
  MountPairCost(const Eigen::Vector3d& reference_ray, const Eigen::Vector3d& current_ray, const Eigen::Vector2d& centre_xy,
                double sigma);
  /// `motion` is (x, y, theta) with theta's cosine and sine; the Jacobians (2 x 3 each: reference state, current
  /// state, motion) are filled when not null.
  Eigen::Vector2d evaluate(const MountAngles& reference, const MountAngles& current, const double* motion, double cos_theta,
                           double sin_theta, Eigen::Matrix<double, 2, 3>* d_reference, Eigen::Matrix<double, 2, 3>* d_current,
                           Eigen::Matrix<double, 2, 3>* d_motion) const;

 private:
  Eigen::Vector3d reference_ray_, current_ray_;
  Eigen::Vector2d centre_xy_;
  double inverse_sigma_;
};

}  // namespace groundslam
