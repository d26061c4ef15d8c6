#include "groundslam/io/CalibrationFile.hpp"

#include <cmath>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/persistence.hpp>
#include <yaml-cpp/yaml.h>

#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"

namespace groundslam {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw InputError(path + ": " + what); }

/// Distortion coefficients of a model into the 5-slot layout (radtan: k1 k2 p1 p2 [k3]; equidistant: k1..k4).
std::array<double, 5> coefficients(const std::vector<double>& values, const std::string& model, const std::string& path) {
  std::array<double, 5> d{};
  const size_t most = model == "equidistant" ? 4 : 5;
  if (values.size() > most || (model == "equidistant" && values.size() != 4 && !values.empty()) ||
      (model == "radtan" && !values.empty() && values.size() < 4)) {
    fail(path, std::to_string(values.size()) + " distortion coefficients for the " + model + " model (radtan: 4 or 5, equidistant: 4)");
  }
  for (size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) fail(path, "a distortion coefficient is not a finite number");
    d[i] = values[i];
  }
  return d;
}

std::string modelName(const std::string& name, const std::string& path) {
  if (name == "plumb_bob" || name == "radtan" || name == "rational_polynomial" || name.empty()) {
    if (name == "rational_polynomial") fail(path, "distortion model rational_polynomial (8 coefficients) is not supported; use plumb_bob / radtan or equidistant");
    return "radtan";
  }
  if (name == "equidistant" || name == "fisheye") return "equidistant";
  fail(path, "unknown distortion model '" + name + "' (plumb_bob, radtan, equidistant)");
}

Calibration fromOpenCv(const std::string& path) {
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    fail(path, std::string("not a readable OpenCV FileStorage file: ") + e.what());
  }
  if (!fs.isOpened()) fail(path, "not a readable OpenCV FileStorage file");
  const auto node = [&](std::initializer_list<const char*> names) {
    for (const char* name : names) {
      if (!fs[name].empty()) return fs[name];
    }
    return cv::FileNode();
  };
  cv::Mat K, D;
  std::string model;
  Calibration c;
  c.format = "opencv";
  try {
    node({"camera_matrix", "cameraMatrix", "K"}) >> K;
    node({"distortion_coefficients", "dist_coeffs", "distCoeffs", "D"}) >> D;
    node({"distortion_model"}) >> model;
    double width = 0.0, height = 0.0;
    node({"image_width", "width"}) >> width;
    node({"image_height", "height"}) >> height;
    if (!(width >= 1.0 && width <= 100000.0 && height >= 1.0 && height <= 100000.0)) fail(path, "image_width / image_height: missing or not an image size");
    c.image_width = static_cast<int>(width);
    c.image_height = static_cast<int>(height);
  } catch (const cv::Exception& e) {
    fail(path, "bad value (camera_matrix, distortion_coefficients, image size): " + e.err);
  }
  if (K.empty() || K.rows != 3 || K.cols != 3) fail(path, "key 'camera_matrix': a 3x3 matrix is needed");
  K.convertTo(K, CV_64F);
  c.fx = K.at<double>(0, 0), c.fy = K.at<double>(1, 1), c.cx = K.at<double>(0, 2), c.cy = K.at<double>(1, 2);
  c.distortion_model = modelName(model, path);
  std::vector<double> values;
  if (!D.empty()) {
    D.convertTo(D, CV_64F);
    values.assign(D.begin<double>(), D.end<double>());
  }
  c.distortion = coefficients(values, c.distortion_model, path);
  return c;
}

int sizeKey(const YAML::Node& node, const std::string& key, const std::string& path) {
  if (!node) fail(path, "key '" + key + "' is missing");
  double value = 0.0;
  try {
    value = node.as<double>();
  } catch (const YAML::Exception&) {
    fail(path, "key '" + key + "': not a number");
  }
  if (!(value >= 1.0 && value <= 100000.0) || value != std::floor(value)) fail(path, "key '" + key + "': not an image size in pixels");
  return static_cast<int>(value);
}

std::string textKey(const YAML::Node& node, const std::string& key, const std::string& path) {
  if (!node) return "";
  try {
    return node.as<std::string>();
  } catch (const YAML::Exception&) {
    fail(path, "key '" + key + "': not a name");
  }
}

std::vector<double> numbers(const YAML::Node& node, const std::string& key, const std::string& path) {
  if (!node || !node.IsSequence()) fail(path, "key '" + key + "': a list of numbers is needed");
  std::vector<double> values;
  for (const auto& item : node) {
    try {
      values.push_back(item.as<double>());
    } catch (const YAML::Exception&) {
      fail(path, "key '" + key + "': not a number");
    }
  }
  return values;
}

Calibration fromRos(const YAML::Node& root, const std::string& path) {
  Calibration c;
  c.format = "ros";
  const std::vector<double> K = numbers(root["camera_matrix"]["data"], "camera_matrix.data", path);
  if (K.size() != 9) fail(path, "key 'camera_matrix.data': 9 numbers (row-major 3x3) are needed");
  c.fx = K[0], c.fy = K[4], c.cx = K[2], c.cy = K[5];
  c.distortion_model = modelName(textKey(root["distortion_model"], "distortion_model", path), path);
  if (root["distortion_coefficients"]) {
    c.distortion = coefficients(numbers(root["distortion_coefficients"]["data"], "distortion_coefficients.data", path),
                                c.distortion_model, path);
  }
  c.image_width = sizeKey(root["image_width"], "image_width", path);
  c.image_height = sizeKey(root["image_height"], "image_height", path);
  return c;
}

Calibration fromKalibr(const YAML::Node& root, const std::string& path) {
  const YAML::Node cam = root["cam0"];
  Calibration c;
  c.format = "kalibr";
  const std::string camera_model = cam["camera_model"] ? textKey(cam["camera_model"], "cam0.camera_model", path) : "pinhole";
  if (camera_model != "pinhole") fail(path, "key 'cam0.camera_model': only pinhole is supported, not '" + camera_model + "'");
  const std::vector<double> k = numbers(cam["intrinsics"], "cam0.intrinsics", path);
  if (k.size() != 4) fail(path, "key 'cam0.intrinsics': [fu, fv, pu, pv] is needed");
  c.fx = k[0], c.fy = k[1], c.cx = k[2], c.cy = k[3];
  c.distortion_model = modelName(textKey(cam["distortion_model"], "cam0.distortion_model", path), path);
  if (cam["distortion_coeffs"]) c.distortion = coefficients(numbers(cam["distortion_coeffs"], "cam0.distortion_coeffs", path), c.distortion_model, path);
  const std::vector<double> size = numbers(cam["resolution"], "cam0.resolution", path);
  if (size.size() != 2) fail(path, "key 'cam0.resolution': [width, height] is needed");
  for (double v : size) {
    if (!(v >= 1.0 && v <= 100000.0) || v != std::floor(v)) fail(path, "key 'cam0.resolution': not an image size in pixels");
  }
  c.image_width = static_cast<int>(size[0]);
  c.image_height = static_cast<int>(size[1]);
  return c;
}

}  // namespace

Calibration readCalibration(const std::string& path) {
  const std::string text = readTextFile(path);
  Calibration c;
  if (text.rfind("%YAML:1.0", 0) == 0 || text.rfind("%YAML 1.0", 0) == 0 || text.find("<opencv_storage>") != std::string::npos) {
    c = fromOpenCv(path);
  } else {
    YAML::Node root;
    try {
      root = YAML::Load(text);
    } catch (const YAML::Exception& e) {
      fail(path, "not a calibration file (YAML: " + e.msg + ")");
    }
    try {
      if (root.IsMap() && root["cam0"]) {
        c = fromKalibr(root, path);
      } else if (root.IsMap() && root["camera_matrix"] && root["camera_matrix"]["data"]) {
        c = fromRos(root, path);
      } else {
        fail(path, "not a calibration file groundslam knows: expected OpenCV FileStorage (camera_matrix), ROS camera_info "
                   "(camera_matrix.data) or Kalibr camchain (cam0)");
      }
    } catch (const YAML::Exception& e) {
      fail(path, "line " + std::to_string(e.mark.line + 1) + ": bad value: " + e.msg);
    }
  }
  if (!(c.fx > 0.0) || !(c.fy > 0.0) || !std::isfinite(c.cx) || !std::isfinite(c.cy)) fail(path, "focal lengths must be positive and finite");
  if (c.image_width <= 0 || c.image_height <= 0) fail(path, "the image size is missing or not positive");
  return c;
}

}  // namespace groundslam
