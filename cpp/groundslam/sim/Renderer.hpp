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

/// A shadow on the ground, fixed to the robot: the ground beyond a straight edge is darkened. The edge is
/// the line {p : direction . p = offset} in the robot frame, softened over `softness_m` (the penumbra).
struct GroundShadow {
  Eigen::Vector2d direction_robot = Eigen::Vector2d::UnitX();  ///< unit normal of the edge, pointing into the shadow
  double offset_m = 0.0;
  double softness_m = 0.003;
  double darkness = 0.0;  ///< 0: no shadow, 1: black
};

class GroundRenderer {
 public:
  /// `supersampling` rays per pixel along each axis, averaged (anti-aliasing).
  GroundRenderer(const CameraModel& camera, int supersampling);

  /// Radiance image (CV_32F, albedo units) seen from T_world_robot with the camera at T_robot_camera.
  cv::Mat render(const GroundTexture& texture, const Pose2& T_world_robot, const Eigen::Isometry3d& T_robot_camera,
                 const GroundShadow& shadow = GroundShadow()) const;

 private:
  CameraModel camera_;
  int supersampling_;
  std::vector<Eigen::Vector2d> rays_;  ///< undistorted normalised rays of all sub-pixels, row-major
};

}  // namespace groundslam::sim
