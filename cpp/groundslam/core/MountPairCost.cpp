#include "groundslam/core/MountPairCost.hpp"

#include <cmath>

namespace groundslam {

Eigen::Vector2d mountGroundPoint(const Eigen::Vector3d& r, const Eigen::Vector2d& centre_xy, const double* state,
                                 Eigen::Matrix<double, 2, 3>* jacobian) {
  const double roll = state[0], pitch = state[1], height = state[2];
  const double cp = std::cos(pitch), sp = std::sin(pitch), cr = std::cos(roll), sr = std::sin(roll);
  // The ray turned by pitch (about y), then by roll (about x).
  const double x1 = cp * r.x() + sp * r.z();
  const double y1 = r.y();
  const double z1 = -sp * r.x() + cp * r.z();
  const double y2 = cr * y1 - sr * z1;
  const double z2 = sr * y1 + cr * z1;
  const double s = -height / z2;  // metres along the turned ray to the ground
  if (jacobian) {
    // d(x1, z1)/d pitch = (z1, -x1); d(y2, z2)/d roll = (-z2, y2); d(y2, z2)/d pitch = (sr x1, -cr x1);
    // ds/dz2 = height / z2^2; ds/dheight = -1 / z2.
    const double ds_dz2 = height / (z2 * z2);
    const double ds_droll = ds_dz2 * y2;
    const double ds_dpitch = ds_dz2 * (-cr * x1);
    (*jacobian)(0, 0) = ds_droll * x1;
    (*jacobian)(1, 0) = ds_droll * y2 + s * (-z2);
    (*jacobian)(0, 1) = ds_dpitch * x1 + s * z1;
    (*jacobian)(1, 1) = ds_dpitch * y2 + s * (sr * x1);
    (*jacobian)(0, 2) = -x1 / z2;
    (*jacobian)(1, 2) = -y2 / z2;
  }
  return {centre_xy.x() + s * x1, centre_xy.y() + s * y2};
}

MountPairCost::MountPairCost(const Eigen::Vector3d& reference_ray, const Eigen::Vector3d& current_ray,
                             const Eigen::Vector2d& centre_xy, double sigma)
    : reference_ray_(reference_ray), current_ray_(current_ray), centre_xy_(centre_xy), inverse_sigma_(1.0 / sigma) {}

bool MountPairCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const double* motion = parameters[2];
  Eigen::Matrix<double, 2, 3> d_reference, d_current;
  const bool want = jacobians != nullptr;
  const Eigen::Vector2d p_ref = mountGroundPoint(reference_ray_, centre_xy_, parameters[0], want ? &d_reference : nullptr);
  const Eigen::Vector2d p_cur = mountGroundPoint(current_ray_, centre_xy_, parameters[1], want ? &d_current : nullptr);
  const double c = std::cos(motion[2]), s = std::sin(motion[2]);
  const Eigen::Matrix2d R = (Eigen::Matrix2d() << c, -s, s, c).finished();
  const Eigen::Vector2d r = (R * p_cur + Eigen::Vector2d(motion[0], motion[1]) - p_ref) * inverse_sigma_;
  residuals[0] = r.x();
  residuals[1] = r.y();
  if (!jacobians) return true;
  using RowMajor23 = Eigen::Matrix<double, 2, 3, Eigen::RowMajor>;
  if (jacobians[0]) {
    Eigen::Map<RowMajor23> J(jacobians[0]);
    J = -inverse_sigma_ * d_reference;
  }
  if (jacobians[1]) {
    Eigen::Map<RowMajor23> J(jacobians[1]);
    J = inverse_sigma_ * R * d_current;
  }
  if (jacobians[2]) {
    Eigen::Map<RowMajor23> J(jacobians[2]);
    J << inverse_sigma_, 0.0, inverse_sigma_ * (-s * p_cur.x() - c * p_cur.y()),  //
        0.0, inverse_sigma_, inverse_sigma_ * (c * p_cur.x() - s * p_cur.y());
  }
  return true;
}

}  // namespace groundslam
