#include "groundslam/pipeline/Config.hpp"

namespace groundslam {

CameraConfig cameraConfigOf(const CameraIntrinsics& k, double mounting_height_m) {
  CameraConfig camera;
  camera.image_width = k.width;
  camera.image_height = k.height;
  camera.fx = k.fx;
  camera.fy = k.fy;
  camera.cx = k.cx;
  camera.cy = k.cy;
  camera.distortion = k.distortion;
  camera.distortion_model = k.model;
  camera.mounting_height_m = mounting_height_m;
  return camera;
}

CameraIntrinsics intrinsicsOf(const CameraConfig& c) {
  CameraIntrinsics k;
  k.width = c.image_width;
  k.height = c.image_height;
  k.fx = c.fx;
  k.fy = c.fy;
  k.cx = c.cx;
  k.cy = c.cy;
  k.distortion = c.distortion;
  k.model = c.distortion_model;
  return k;
}

const std::vector<std::string>& requiredConfigKeys() {
  static const std::vector<std::string> keys = {
      "camera.image_width", "camera.image_height", "camera.fx",         "camera.fy",
      "camera.cx",          "camera.cy",           "camera.distortion", "camera.mounting_height_m"};
  return keys;
}

}  // namespace groundslam
