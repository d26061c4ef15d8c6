#include "groundslam/pipeline/Config.hpp"

namespace groundslam {

const std::vector<std::string>& requiredConfigKeys() {
  static const std::vector<std::string> keys = {
      "camera.image_width", "camera.image_height", "camera.fx",         "camera.fy",
      "camera.cx",          "camera.cy",           "camera.distortion", "camera.mounting_height_m"};
  return keys;
}

}  // namespace groundslam
