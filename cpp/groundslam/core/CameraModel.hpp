#pragma once
// A calibrated pinhole camera with OpenCV distortion, mounted on the robot at T_robot_camera.
// Maps pixels to metric points on the ground plane z = 0 of the robot frame (docs/conventions.md).

#include <array>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace groundslam {

/// radtan: OpenCV's radial-tangential model (k1 k2 p1 p2 k3; ROS plumb_bob, Kalibr radtan). equidistant:
/// the fisheye model of cv::fisheye and Kalibr (k1 k2 k3 k4 in the first four coefficients; theta_d = theta (1 +
/// k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)).
enum class DistortionModel { radtan, equidistant };

struct CameraIntrinsics {
  int width = 0;                               ///< image width, pixels
  int height = 0;                              ///< image height, pixels
  double fx = 0.0, fy = 0.0;                   ///< focal lengths, pixels
  double cx = 0.0, cy = 0.0;                   ///< principal point, pixels
  std::array<double, 5> distortion{};          ///< radtan: k1 k2 p1 p2 k3; equidistant: k1 k2 k3 k4 (fifth unused)
  DistortionModel model = DistortionModel::radtan;
};

/// The default mount: camera `height_m` above the robot origin looking straight down,
/// image u-axis = robot +x, image v-axis = robot -y.
Eigen::Isometry3d defaultCameraMount(double height_m);

class CameraModel {
 public:
  CameraModel(const CameraIntrinsics& intrinsics, const Eigen::Isometry3d& T_robot_camera);

  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  const Eigen::Isometry3d& T_robot_camera() const { return T_robot_camera_; }
  bool hasDistortion() const;

  /// Undistorted normalised image coordinates (x/z, y/z) of pixels.
  std::vector<Eigen::Vector2d> normalisedRays(const std::vector<Eigen::Vector2d>& pixels) const;

  /// Ground point (robot frame, metres) seen at a pixel; empty when the ray misses the ground.
  std::optional<Eigen::Vector2d> pixelToGround(const Eigen::Vector2d& pixel) const;
  std::vector<std::optional<Eigen::Vector2d>> pixelsToGround(const std::vector<Eigen::Vector2d>& pixels) const;

  /// Intersects a normalised camera ray with the ground for a given mount (used with jittered mounts).
  static std::optional<Eigen::Vector2d> intersectGround(const Eigen::Vector2d& normalised_ray,
                                                        const Eigen::Isometry3d& T_robot_camera);

  /// Pixel at which a ground point (robot frame) is seen, with distortion; empty when behind the camera.
  std::optional<Eigen::Vector2d> groundToPixel(const Eigen::Vector2d& p_robot) const;

  /// The image's footprint on the ground (robot frame): the border pixels' ground points, a convex polygon
  /// for a downward camera. Empty when part of the border looks above the horizon.
  std::vector<Eigen::Vector2d> groundFootprint() const;

  /// Metres on the ground per pixel at the image centre (used to size simulated textures and maps).
  double groundSampleDistance() const;

 private:
  CameraIntrinsics intrinsics_;
  Eigen::Isometry3d T_robot_camera_;
};

}  // namespace groundslam
