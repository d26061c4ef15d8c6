#include "groundslam/core/CameraModel.hpp"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace groundslam {

Eigen::Isometry3d defaultCameraMount(double height_m) {
  Eigen::Matrix3d R_robot_camera;
  R_robot_camera << 1.0, 0.0, 0.0,  //
      0.0, -1.0, 0.0,               //
      0.0, 0.0, -1.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R_robot_camera;
  T.translation() = Eigen::Vector3d(0.0, 0.0, height_m);
  return T;
}

CameraModel::CameraModel(const CameraIntrinsics& intrinsics, const Eigen::Isometry3d& T_robot_camera)
    : intrinsics_(intrinsics), T_robot_camera_(T_robot_camera) {}

bool CameraModel::hasDistortion() const {
  for (double k : intrinsics_.distortion) {
    if (k != 0.0) return true;
  }
  return false;
}

std::vector<Eigen::Vector2d> CameraModel::normalisedRays(const std::vector<Eigen::Vector2d>& pixels) const {
  std::vector<Eigen::Vector2d> rays(pixels.size());
  if (!hasDistortion()) {
    for (size_t i = 0; i < pixels.size(); ++i) {
      rays[i] = {(pixels[i].x() - intrinsics_.cx) / intrinsics_.fx, (pixels[i].y() - intrinsics_.cy) / intrinsics_.fy};
    }
    return rays;
  }
  if (pixels.empty()) return rays;
  std::vector<cv::Point2d> distorted(pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i) distorted[i] = {pixels[i].x(), pixels[i].y()};
  const cv::Matx33d K(intrinsics_.fx, 0.0, intrinsics_.cx, 0.0, intrinsics_.fy, intrinsics_.cy, 0.0, 0.0, 1.0);
  const cv::Mat D(1, 5, CV_64F, const_cast<double*>(intrinsics_.distortion.data()));
  std::vector<cv::Point2d> undistorted;
  // The default 5 iterations leave micrometre errors under strong distortion; iterate to convergence.
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12);
  if (intrinsics_.model == DistortionModel::equidistant) {
    const cv::Vec4d D4(intrinsics_.distortion[0], intrinsics_.distortion[1], intrinsics_.distortion[2], intrinsics_.distortion[3]);
    cv::fisheye::undistortPoints(distorted, undistorted, K, D4, cv::noArray(), cv::noArray(), criteria);
  } else {
    cv::undistortPoints(distorted, undistorted, K, D, cv::noArray(), cv::noArray(), criteria);
  }
  for (size_t i = 0; i < pixels.size(); ++i) rays[i] = {undistorted[i].x, undistorted[i].y};
  return rays;
}

std::optional<Eigen::Vector2d> CameraModel::intersectGround(const Eigen::Vector2d& normalised_ray,
                                                            const Eigen::Isometry3d& T_robot_camera) {
  const Eigen::Vector3d direction = T_robot_camera.linear() * Eigen::Vector3d(normalised_ray.x(), normalised_ray.y(), 1.0);
  const Eigen::Vector3d origin = T_robot_camera.translation();
  // The ray origin + s * direction reaches z = 0 at s = -origin.z / direction.z, which must be ahead.
  if (direction.z() >= -1e-12) return std::nullopt;
  const double s = -origin.z() / direction.z();
  if (s <= 0.0) return std::nullopt;
  const Eigen::Vector3d hit = origin + s * direction;
  return Eigen::Vector2d(hit.x(), hit.y());
}

std::optional<Eigen::Vector2d> CameraModel::pixelToGround(const Eigen::Vector2d& pixel) const {
  return pixelsToGround({pixel}).front();
}

std::vector<std::optional<Eigen::Vector2d>> CameraModel::pixelsToGround(const std::vector<Eigen::Vector2d>& pixels) const {
  const std::vector<Eigen::Vector2d> rays = normalisedRays(pixels);
  std::vector<std::optional<Eigen::Vector2d>> points(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) points[i] = intersectGround(rays[i], T_robot_camera_);
  return points;
}

std::optional<Eigen::Vector2d> CameraModel::groundToPixel(const Eigen::Vector2d& p_robot) const {
  const Eigen::Vector3d p_camera = T_robot_camera_.inverse() * Eigen::Vector3d(p_robot.x(), p_robot.y(), 0.0);
  if (p_camera.z() <= 0.0) return std::nullopt;
  const double xn = p_camera.x() / p_camera.z(), yn = p_camera.y() / p_camera.z();
  const auto& d = intrinsics_.distortion;
  if (intrinsics_.model == DistortionModel::equidistant) {
    // The angle from the optical axis, distorted by the polynomial, along the same direction in the image.
    const double r = std::hypot(xn, yn);
    const double theta = std::atan(r), t2 = theta * theta;
    const double theta_d = theta * (1.0 + t2 * (d[0] + t2 * (d[1] + t2 * (d[2] + t2 * d[3]))));
    const double scale = r > 1e-12 ? theta_d / r : 1.0;
    return Eigen::Vector2d(intrinsics_.fx * xn * scale + intrinsics_.cx, intrinsics_.fy * yn * scale + intrinsics_.cy);
  }
  // k1 k2 p1 p2 k3, OpenCV's radial-tangential model
  const double r2 = xn * xn + yn * yn;
  const double radial = 1.0 + d[0] * r2 + d[1] * r2 * r2 + d[4] * r2 * r2 * r2;
  const double xd = xn * radial + 2.0 * d[2] * xn * yn + d[3] * (r2 + 2.0 * xn * xn);
  const double yd = yn * radial + d[2] * (r2 + 2.0 * yn * yn) + 2.0 * d[3] * xn * yn;
  return Eigen::Vector2d(intrinsics_.fx * xd + intrinsics_.cx, intrinsics_.fy * yd + intrinsics_.cy);
}

std::vector<Eigen::Vector2d> CameraModel::groundFootprint() const {
  const double w = intrinsics_.width - 0.5, h = intrinsics_.height - 0.5;
  std::vector<Eigen::Vector2d> border;
  constexpr int kPerSide = 8;  // several points per side follow a distorted border
  for (int i = 0; i < kPerSide; ++i) border.emplace_back(-0.5 + (w + 0.5) * i / kPerSide, -0.5);
  for (int i = 0; i < kPerSide; ++i) border.emplace_back(w, -0.5 + (h + 0.5) * i / kPerSide);
  for (int i = 0; i < kPerSide; ++i) border.emplace_back(w - (w + 0.5) * i / kPerSide, h);
  for (int i = 0; i < kPerSide; ++i) border.emplace_back(-0.5, h - (h + 0.5) * i / kPerSide);
  std::vector<Eigen::Vector2d> polygon;
  for (const auto& p : pixelsToGround(border)) {
    if (!p) return {};
    polygon.push_back(*p);
  }
  return polygon;
}

double CameraModel::groundSampleDistance() const {
  const Eigen::Vector2d centre(intrinsics_.cx, intrinsics_.cy);
  const auto a = pixelToGround(centre);
  const auto b = pixelToGround(centre + Eigen::Vector2d(1.0, 0.0));
  if (!a || !b) return T_robot_camera_.translation().z() / intrinsics_.fx;
  return (*b - *a).norm();
}

}  // namespace groundslam
