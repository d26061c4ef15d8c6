#include "groundslam/core/Pose2.hpp"

#include <cmath>

namespace groundslam {

double wrapAngle(double angle_rad) {
  double wrapped = std::remainder(angle_rad, 2.0 * M_PI);  // in [-pi, pi]
  if (wrapped <= -M_PI) wrapped += 2.0 * M_PI;
  return wrapped;
}

Pose2::Pose2(double x_m, double y_m, double theta_rad) : x(x_m), y(y_m), theta(wrapAngle(theta_rad)) {}

Pose2 Pose2::fromMatrix(const Eigen::Matrix3d& T) {
  return Pose2(T(0, 2), T(1, 2), std::atan2(T(1, 0), T(0, 0)));
}

Eigen::Matrix3d Pose2::matrix() const {
  const double c = std::cos(theta), s = std::sin(theta);
  Eigen::Matrix3d T;
  T << c, -s, x, s, c, y, 0.0, 0.0, 1.0;
  return T;
}

Pose2 Pose2::operator*(const Pose2& T_b_c) const {
  const Eigen::Vector2d t = (*this) * T_b_c.translation();
  return Pose2(t.x(), t.y(), theta + T_b_c.theta);
}

Eigen::Matrix2d Pose2::rotation() const {
  const double c = std::cos(theta), s = std::sin(theta);
  return (Eigen::Matrix2d() << c, -s, s, c).finished();
}

Eigen::Vector2d Pose2::operator*(const Eigen::Vector2d& p_b) const { return rotation() * p_b + translation(); }

Pose2 Pose2::inverse() const {
  const double c = std::cos(theta), s = std::sin(theta);
  return Pose2(-c * x - s * y, s * x - c * y, -theta);
}

Pose2 between(const Pose2& T_w_a, const Pose2& T_w_b) { return T_w_a.inverse() * T_w_b; }

}  // namespace groundslam
