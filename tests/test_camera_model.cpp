// Pixel -> ground projection against OpenCV's own forward projection of known ground points.
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include "groundslam/core/CameraModel.hpp"

using namespace groundslam;

namespace {

CameraIntrinsics distortedCamera() {
  CameraIntrinsics k;
  k.width = 640;
  k.height = 480;
  k.fx = 600.0;
  k.fy = 590.0;
  k.cx = 330.0;
  k.cy = 235.0;
  k.distortion = {-0.28, 0.11, 0.0012, -0.0008, -0.02};
  return k;
}

/// Projects ground points (robot frame) with cv::projectPoints, then maps the pixels back.
double worstRoundTripError(const CameraModel& camera) {
  const Eigen::Isometry3d T_camera_robot = camera.T_robot_camera().inverse();
  const auto& k = camera.intrinsics();
  std::vector<cv::Point3d> points_camera;
  std::vector<Eigen::Vector2d> ground;
  for (double x = -0.08; x <= 0.08; x += 0.02) {
    for (double y = -0.06; y <= 0.06; y += 0.02) {
      const Eigen::Vector2d p_robot = camera.T_robot_camera().translation().head<2>() + Eigen::Vector2d(x, y);
      const Eigen::Vector3d p_camera = T_camera_robot * Eigen::Vector3d(p_robot.x(), p_robot.y(), 0.0);
      points_camera.emplace_back(p_camera.x(), p_camera.y(), p_camera.z());
      ground.push_back(p_robot);
    }
  }
  std::vector<cv::Point2d> pixels_cv;
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  cv::projectPoints(points_camera, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, std::vector<double>(k.distortion.begin(), k.distortion.end()),
                    pixels_cv);
  std::vector<Eigen::Vector2d> pixels;
  for (const auto& p : pixels_cv) pixels.emplace_back(p.x, p.y);
  const auto back = camera.pixelsToGround(pixels);
  double worst = 0.0;
  for (size_t i = 0; i < back.size(); ++i) {
    EXPECT_TRUE(back[i].has_value());
    if (back[i]) worst = std::max(worst, (*back[i] - ground[i]).norm());
    // Our forward model agrees with OpenCV's.
    const auto pixel = camera.groundToPixel(ground[i]);
    EXPECT_TRUE(pixel.has_value());
    if (pixel) {
      EXPECT_LT((*pixel - pixels[i]).norm(), 1e-9);
    }
  }
  return worst;
}

}  // namespace

TEST(CameraModel, DefaultMountMatchesConventions) {
  const Eigen::Isometry3d T = defaultCameraMount(0.25);
  // Image u-axis = robot +x, image v-axis = robot -y, optical axis down, camera 0.25 m up.
  EXPECT_TRUE(T.linear().col(0).isApprox(Eigen::Vector3d(1, 0, 0)));
  EXPECT_TRUE(T.linear().col(1).isApprox(Eigen::Vector3d(0, -1, 0)));
  EXPECT_TRUE(T.linear().col(2).isApprox(Eigen::Vector3d(0, 0, -1)));
  EXPECT_DOUBLE_EQ(T.translation().z(), 0.25);
}

TEST(CameraModel, StraightDownReducesToThePapersScaling) {
  CameraIntrinsics k = distortedCamera();
  k.distortion = {};
  const CameraModel camera(k, defaultCameraMount(0.25));
  // z_C = K^-1 (u, v, 1) d, then x_R = x_C, y_R = -y_C.
  const auto p = camera.pixelToGround({k.cx + 120.0, k.cy + 59.0});
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->x(), 120.0 / 600.0 * 0.25, 1e-12);
  EXPECT_NEAR(p->y(), -59.0 / 590.0 * 0.25, 1e-12);
  EXPECT_NEAR(camera.groundSampleDistance(), 0.25 / 600.0, 1e-12);
}

TEST(CameraModel, StraightDownWithDistortionRoundTripsThroughOpenCV) {
  const CameraModel camera(distortedCamera(), defaultCameraMount(0.25));
  EXPECT_LT(worstRoundTripError(camera), 1e-6);
}

TEST(CameraModel, TiltedCameraWithDistortionRoundTripsThroughOpenCV) {
  Eigen::Isometry3d T = defaultCameraMount(0.3);
  // Pitched 20 degrees about the robot's y-axis, rolled 5 degrees, shifted forward.
  T.linear() = (Eigen::AngleAxisd(20.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d::UnitX())).toRotationMatrix() * T.linear();
  T.translation() = Eigen::Vector3d(0.1, 0.02, 0.3);
  const CameraModel camera(distortedCamera(), T);
  EXPECT_LT(worstRoundTripError(camera), 1e-6);
}

TEST(CameraModel, RayAboveTheHorizonMissesTheGround) {
  Eigen::Isometry3d T = defaultCameraMount(0.3);
  T.linear() = Eigen::AngleAxisd(85.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix() * T.linear();
  CameraIntrinsics k = distortedCamera();
  k.distortion = {};
  const CameraModel camera(k, T);
  // With the camera pitched 85 degrees, image rows far from the centre look above the horizon on one side.
  const auto missed = camera.pixelToGround({0.0, k.cy});
  const auto hit = camera.pixelToGround({k.width - 1.0, k.cy});
  EXPECT_NE(missed.has_value(), hit.has_value());
}
