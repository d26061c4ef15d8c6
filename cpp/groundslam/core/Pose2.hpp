#pragma once
// SE(2) rigid transforms on the ground plane. Named by frames: T_a_b maps points in frame b to frame a.

#include <Eigen/Core>

namespace groundslam {

/// Wraps an angle to (-pi, pi].
double wrapAngle(double angle_rad);

struct Pose2 {
  double x = 0.0;      ///< translation, metres
  double y = 0.0;      ///< translation, metres
  double theta = 0.0;  ///< rotation, radians, kept in (-pi, pi]

  Pose2() = default;
  Pose2(double x_m, double y_m, double theta_rad);

  static Pose2 identity() { return Pose2(); }
  static Pose2 fromMatrix(const Eigen::Matrix3d& T);

  Eigen::Matrix3d matrix() const;
  Eigen::Vector2d translation() const { return {x, y}; }
  /// The rotation matrix R(theta): compute it once to transform many points (p_a = R p_b + t).
  Eigen::Matrix2d rotation() const;

  /// T_a_c = T_a_b * T_b_c
  Pose2 operator*(const Pose2& T_b_c) const;
  /// p_a = T_a_b * p_b
  Eigen::Vector2d operator*(const Eigen::Vector2d& p_b) const;
  /// T_b_a from T_a_b
  Pose2 inverse() const;
};

/// T_a_b = T_w_a^-1 * T_w_b: the pose of b seen from a.
Pose2 between(const Pose2& T_w_a, const Pose2& T_w_b);

}  // namespace groundslam
