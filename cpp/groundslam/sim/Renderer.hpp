#pragma once
// Renders what a downward camera sees of a textured ground plane: every pixel's ray is intersected
// with the plane (exact for any mount), mapped to the world and sampled from the texture.

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/Pose2.hpp"
#include "groundslam/sim/Texture.hpp"

namespace groundslam::sim {

class GroundRenderer {
 public:
  /// `supersampling` rays per pixel along each axis, averaged (anti-aliasing).
  GroundRenderer(const CameraModel& camera, int supersampling);

  /// Radiance image (CV_32F, albedo units) seen from T_world_robot with the camera at T_robot_camera.
  cv::Mat render(const GroundTexture& texture, const Pose2& T_world_robot, const Eigen::Isometry3d& T_robot_camera) const;

 private:
  CameraModel camera_;
  int supersampling_;
  std::vector<Eigen::Vector2d> rays_;  ///< undistorted normalised rays of all sub-pixels, row-major
};

}  // namespace groundslam::sim
