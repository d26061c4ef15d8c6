#include "groundslam/core/MountPairCost.hpp"

#include <cmath>

namespace groundslam {

MountAngles::MountAngles(const double* state)
    : cr(std::cos(state[0])), sr(std::sin(state[0])), cp(std::cos(state[1])), sp(std::sin(state[1])), height(state[2]) {}

Eigen::Vector2d mountGroundPoint(const Eigen::Vector3d& r, const Eigen::Vector2d& centre_xy, const MountAngles& a,
                                 Eigen::Matrix<double, 2, 3>* jacobian) {
  // The ray turned by pitch (about y), then by roll (about x).
  const double x1 = a.cp * r.x() + a.sp * r.z();
  const double y1 = r.y();
  const double z1 = -a.sp * r.x() + a.cp * r.z();
  const double y2 = a.cr * y1 - a.sr * z1;
  const double z2 = a.sr * y1 + a.cr * z1;
  const double s = -a.height / z2;  // metres along the turned ray to the ground
  if (jacobian) {
    // d(x1, z1)/d pitch = (z1, -x1); d(y2, z2)/d roll = (-z2, y2); d(y2, z2)/d pitch = (sr x1, -cr x1);
    // ds/dz2 = height / z2^2; ds/dheight = -1 / z2.
    const double ds_dz2 = a.height / (z2 * z2);
    const double ds_droll = ds_dz2 * y2;
    const double ds_dpitch = ds_dz2 * (-a.cr * x1);
    (*jacobian)(0, 0) = ds_droll * x1;
    (*jacobian)(1, 0) = ds_droll * y2 + s * (-z2);
    (*jacobian)(0, 1) = ds_dpitch * x1 + s * z1;
    (*jacobian)(1, 1) = ds_dpitch * y2 + s * (a.sr * x1);
    (*jacobian)(0, 2) = -x1 / z2;
    (*jacobian)(1, 2) = -y2 / z2;
  }
  return {centre_xy.x() + s * x1, centre_xy.y() + s * y2};
}

MountPairCost::MountPairCost(const Eigen::Vector3d& reference_ray, const Eigen::Vector3d& current_ray,
                             const Eigen::Vector2d& centre_xy, double sigma)
    : reference_ray_(reference_ray), current_ray_(current_ray), centre_xy_(centre_xy), inverse_sigma_(1.0 / sigma) {}

Eigen::Vector2d MountPairCost::evaluate(const MountAngles& reference, const MountAngles& current, const double* motion,
                                        double c, double s, Eigen::Matrix<double, 2, 3>* d_reference,
                                        Eigen::Matrix<double, 2, 3>* d_current, Eigen::Matrix<double, 2, 3>* d_motion) const {
  Eigen::Matrix<double, 2, 3> ground_reference, ground_current;
  const bool want = d_reference || d_current;
  const Eigen::Vector2d p_ref = mountGroundPoint(reference_ray_, centre_xy_, reference, want ? &ground_reference : nullptr);
  const Eigen::Vector2d p_cur = mountGroundPoint(current_ray_, centre_xy_, current, want ? &ground_current : nullptr);
  Eigen::Matrix2d R;
  R << c, -s, s, c;
  if (d_reference) *d_reference = -inverse_sigma_ * ground_reference;
  if (d_current) *d_current = inverse_sigma_ * R * ground_current;
  if (d_motion) {
    *d_motion << inverse_sigma_, 0.0, inverse_sigma_ * (-s * p_cur.x() - c * p_cur.y()),  //
        0.0, inverse_sigma_, inverse_sigma_ * (c * p_cur.x() - s * p_cur.y());
  }
  return (R * p_cur + Eigen::Vector2d(motion[0], motion[1]) - p_ref) * inverse_sigma_;
}

}  // namespace groundslam
