// Calibration files from other tools (OpenCV, ROS camera_info, Kalibr) and the fisheye (equidistant) model.
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>

#include "TestFiles.hpp"
#include "groundslam/core/CameraModel.hpp"
#include "groundslam/io/CalibrationFile.hpp"
#include "groundslam/io/ConfigYaml.hpp"

using namespace groundslam;
using groundslam::testing::inputErrorOf;
using groundslam::testing::scratchDir;
using groundslam::testing::writeText;

TEST(Calibration, ReadsOpenCvFileStorageYamlAndXml) {
  const auto dir = scratchDir();
  for (const char* name : {"cam.yaml", "cam.xml"}) {
    cv::FileStorage fs((dir / name).string(), cv::FileStorage::WRITE);
    fs << "image_width" << 640 << "image_height" << 480;
    fs << "camera_matrix" << cv::Mat((cv::Mat_<double>(3, 3) << 500.5, 0, 321.25, 0, 501.5, 239.75, 0, 0, 1));
    fs << "distortion_coefficients" << cv::Mat((cv::Mat_<double>(1, 5) << -0.1, 0.02, 0.001, -0.002, 0.003));
    fs.release();
    const Calibration c = readCalibration((dir / name).string());
    EXPECT_EQ(c.format, "opencv");
    EXPECT_EQ(c.image_width, 640);
    EXPECT_EQ(c.image_height, 480);
    EXPECT_DOUBLE_EQ(c.fx, 500.5);
    EXPECT_DOUBLE_EQ(c.fy, 501.5);
    EXPECT_DOUBLE_EQ(c.cx, 321.25);
    EXPECT_DOUBLE_EQ(c.cy, 239.75);
    EXPECT_DOUBLE_EQ(c.distortion[4], 0.003);
    EXPECT_EQ(c.distortion_model, "radtan");
  }
}

TEST(Calibration, ReadsRosCameraInfoAndKalibrWithFisheye) {
  const auto dir = scratchDir();
  writeText(dir / "ost.yaml",
            "image_width: 1600\nimage_height: 1200\ncamera_name: down\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
            "  data: [2195.7, 0, 820.7, 0, 2195.5, 606.2, 0, 0, 1]\ndistortion_model: plumb_bob\n"
            "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0.01, -0.02, 0, 0, 0.005]\n");
  const Calibration ros = readCalibration((dir / "ost.yaml").string());
  EXPECT_EQ(ros.format, "ros");
  EXPECT_DOUBLE_EQ(ros.fx, 2195.7);
  EXPECT_DOUBLE_EQ(ros.cy, 606.2);
  EXPECT_DOUBLE_EQ(ros.distortion[1], -0.02);
  writeText(dir / "camchain.yaml",
            "cam0:\n  camera_model: pinhole\n  intrinsics: [400.0, 401.0, 319.5, 239.5]\n  distortion_model: equidistant\n"
            "  distortion_coeffs: [0.1, -0.05, 0.01, -0.002]\n  resolution: [640, 480]\n  rostopic: /cam0/image_raw\n");
  const Calibration kalibr = readCalibration((dir / "camchain.yaml").string());
  EXPECT_EQ(kalibr.format, "kalibr");
  EXPECT_EQ(kalibr.distortion_model, "equidistant");
  EXPECT_DOUBLE_EQ(kalibr.distortion[3], -0.002);
  EXPECT_EQ(kalibr.image_width, 640);
  // Over a camera.yaml that gives only the mount: intrinsics from the calibration, the mount kept.
  writeText(dir / "camera.yaml", "camera:\n  image_width: 1\n  image_height: 1\n  fx: 1\n  fy: 1\n  cx: 0\n  cy: 0\n"
                                 "  distortion: [0, 0, 0, 0, 0]\n  mounting_height_m: 0.3\n");
  const Config config = loadDatasetConfig((dir / "camera.yaml").string(), "", (dir / "camchain.yaml").string()).config;
  EXPECT_EQ(config.camera.image_width, 640);
  EXPECT_DOUBLE_EQ(config.camera.fy, 401.0);
  EXPECT_EQ(config.camera.distortion_model, DistortionModel::equidistant);
  EXPECT_DOUBLE_EQ(config.camera.mounting_height_m, 0.3);
}

TEST(Calibration, UnknownOrIncompleteFilesAreNamed) {
  const auto dir = scratchDir();
  writeText(dir / "other.yaml", "foo: 1\n");
  EXPECT_NE(inputErrorOf([&] { readCalibration((dir / "other.yaml").string()); }).find("other.yaml: not a calibration file"),
            std::string::npos);
  writeText(dir / "short.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix:\n  data: [1, 0, 0, 0, 1]\n");
  EXPECT_NE(inputErrorOf([&] { readCalibration((dir / "short.yaml").string()); }).find("camera_matrix.data"), std::string::npos);
  writeText(dir / "fish.yaml", "cam0:\n  intrinsics: [400, 400, 320, 240]\n  distortion_model: equidistant\n"
                               "  distortion_coeffs: [0.1, 0.2]\n  resolution: [640, 480]\n");
  EXPECT_NE(inputErrorOf([&] { readCalibration((dir / "fish.yaml").string()); }).find("2 distortion coefficients"),
            std::string::npos);
}

TEST(CameraModel, EquidistantFisheyeRoundTripsAndMatchesOpenCv) {
  CameraIntrinsics k;
  k.width = 640, k.height = 480, k.fx = 300.0, k.fy = 301.0, k.cx = 322.0, k.cy = 238.0;
  k.distortion = {0.08, -0.03, 0.01, -0.002, 0.0};
  k.model = DistortionModel::equidistant;
  const CameraModel camera(k, defaultCameraMount(0.25));
  for (const Eigen::Vector2d& p : {Eigen::Vector2d(0.05, 0.03), Eigen::Vector2d(-0.12, 0.09), Eigen::Vector2d(0.2, -0.15)}) {
    const auto pixel = camera.groundToPixel(p);
    ASSERT_TRUE(pixel);
    // Against OpenCV's own fisheye projection of the same camera point.
    const Eigen::Vector3d pc = camera.T_robot_camera().inverse() * Eigen::Vector3d(p.x(), p.y(), 0.0);
    std::vector<cv::Point3d> object = {{pc.x(), pc.y(), pc.z()}};
    std::vector<cv::Point2d> projected;
    cv::fisheye::projectPoints(object, projected, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0),
                               cv::Matx33d(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1), cv::Vec4d(0.08, -0.03, 0.01, -0.002));
    EXPECT_NEAR(pixel->x(), projected[0].x, 1e-9);
    EXPECT_NEAR(pixel->y(), projected[0].y, 1e-9);
    const auto back = camera.pixelToGround(*pixel);
    ASSERT_TRUE(back);
    EXPECT_NEAR((*back - p).norm(), 0.0, 1e-9);
  }
}
