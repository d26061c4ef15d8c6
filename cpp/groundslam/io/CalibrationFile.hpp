#pragma once
// Camera calibrations as other tools write them: OpenCV's FileStorage (YAML or XML: camera_matrix,
// distortion_coefficients, image_width, image_height), ROS camera_info (ost.yaml from camera_calibration:
// camera_matrix.data, distortion_model plumb_bob | equidistant, distortion_coefficients.data) and Kalibr's
// camchain (cam0: intrinsics [fu fv pu pv], distortion_model radtan | equidistant, distortion_coeffs, resolution).
// The format is detected from the content. They give the intrinsics and distortion; the mount (height,
// T_robot_camera) still comes from camera.yaml or --config.

#include <array>
#include <string>


namespace groundslam {

/// A camera's intrinsics as a calibration file gives them.
struct Calibration {
  std::string format;  ///< what the file was read as: "opencv", "ros" or "kalibr"
  int image_width = 0, image_height = 0;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  std::array<double, 5> distortion{};
  std::string distortion_model = "radtan";
};

/// Reads a calibration file. Throws InputError naming the file and the missing or bad key.
Calibration readCalibration(const std::string& path);

}  // namespace groundslam
