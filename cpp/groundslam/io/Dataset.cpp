#include "groundslam/io/Dataset.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/TextParsing.hpp"

namespace fs = std::filesystem;

namespace groundslam {
namespace {

bool isImageFile(const fs::path& path) {
  static const std::set<std::string> extensions = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm"};
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extensions.count(ext) > 0;
}

std::optional<std::string> cameraYamlIn(const fs::path& folder) {
  const fs::path candidate = folder / "camera.yaml";
  if (fs::exists(candidate)) return candidate.string();
  return std::nullopt;
}

Dataset openImageFolder(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && isImageFile(entry.path())) names.push_back(entry.path().filename().string());
  }
  if (names.empty()) throw InputError(folder.string() + ": folder contains no images (png, jpg, bmp, tif, pgm)");
  std::sort(names.begin(), names.end(), naturalLess);
  Dataset dataset;
  dataset.source = folder.string();
  dataset.camera_yaml = cameraYamlIn(folder);
  for (size_t i = 0; i < names.size(); ++i) {
    dataset.frames.push_back({(folder / names[i]).string(), static_cast<double>(i), std::nullopt, true});
  }
  return dataset;
}

Eigen::Matrix3d parsePoseLine(const std::string& line, const std::string& file, int line_number) {
  const std::vector<double> v = parseNumbers(line, file, line_number);
  if (v.size() != 9) {
    throw InputError(file + ":" + std::to_string(line_number) + ": expected 9 numbers (row-major 3x3 A), got " +
                     std::to_string(v.size()));
  }
  Eigen::Matrix3d A;
  A << v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8];
  return A;
}

Dataset openHdGroundList(const fs::path& list, bool with_poses) {
  std::istringstream in(readTextFile(list.string()));
  Dataset dataset;
  dataset.source = list.string();
  dataset.camera_yaml = cameraYamlIn(list.parent_path());
  const std::string file = list.string();
  std::string line;
  bool expect_pose = false;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string text = trim(line);
    if (text.empty()) continue;
    if (expect_pose) {
      const bool unreliable = text.rfind("* ", 0) == 0;
      dataset.frames.back().map_from_image = parsePoseLine(unreliable ? text.substr(2) : text, file, line_number);
      dataset.frames.back().pose_reliable = !unreliable;
      expect_pose = false;
      continue;
    }
    const fs::path image = list.parent_path() / text;
    if (!fs::exists(image)) {
      throw InputError(file + ":" + std::to_string(line_number) + ": image '" + image.string() + "' not found");
    }
    dataset.frames.push_back({image.string(), static_cast<double>(dataset.frames.size()), std::nullopt, true});
    expect_pose = with_poses;
  }
  if (expect_pose) throw InputError(file + ":" + std::to_string(line_number) + ": image without a pose line");
  if (dataset.frames.empty()) throw InputError(file + ": the list names no images");
  return dataset;
}

}  // namespace

bool Dataset::hasGroundTruth() const {
  return std::any_of(frames.begin(), frames.end(), [](const DatasetFrame& f) { return f.map_from_image.has_value(); });
}

Dataset openDataset(const std::string& path) {
  const fs::path p(path);
  if (!fs::exists(p)) throw InputError(path + ": no such file or folder");
  if (fs::is_directory(p)) return openImageFolder(p);
  const std::string ext = p.extension().string();
  if (ext == ".txt") return openHdGroundList(p, true);
  if (ext == ".test") return openHdGroundList(p, false);
  throw InputError(path + ": not a dataset: expected an HD Ground list (.txt, .test) or an image folder");
}

Pose2 robotPoseFromMapHomography(const Eigen::Matrix3d& A, double cx, double cy, double meters_per_pixel) {
  const Eigen::Vector3d m = A * Eigen::Vector3d(cx, cy, 1.0);
  return Pose2(meters_per_pixel * m.x() / m.z(), -meters_per_pixel * m.y() / m.z(), std::atan2(-A(1, 0), A(0, 0)));
}

Eigen::Matrix3d mapHomographyFromRobotPose(const Pose2& T_world_robot, const CameraIntrinsics& intrinsics,
                                           double meters_per_pixel) {
  // Image pixel -> robot point (default mount): x_R = (u - cx) h / fx, y_R = -(v - cy) h / fy, with h / fx = s.
  // Robot -> world by T_world_robot, world -> map pixel: m_x = x_W / s, m_y = -y_W / s.
  const double s = meters_per_pixel, aspect = intrinsics.fx / intrinsics.fy;
  Eigen::Matrix3d pixel_to_robot;
  pixel_to_robot << s, 0.0, -s * intrinsics.cx, 0.0, -s * aspect, s * aspect * intrinsics.cy, 0.0, 0.0, 1.0;
  Eigen::Matrix3d world_to_map;
  world_to_map << 1.0 / s, 0.0, 0.0, 0.0, -1.0 / s, 0.0, 0.0, 0.0, 1.0;
  return world_to_map * T_world_robot.matrix() * pixel_to_robot;
}

Trajectory groundTruthOf(const Dataset& dataset, const Config& config) {
  const double meters_per_pixel =
      config.dataset.map_meters_per_pixel.value_or(config.camera.mounting_height_m / config.camera.fx);
  Trajectory poses;
  for (const auto& frame : dataset.frames) {
    if (!frame.map_from_image || !frame.pose_reliable) continue;
    poses.push_back({frame.timestamp, robotPoseFromMapHomography(*frame.map_from_image, config.camera.cx,
                                                                 config.camera.cy, meters_per_pixel)});
  }
  return poses;
}

std::string formatHdGroundList(const std::vector<std::string>& relative_image_paths,
                               const std::vector<Eigen::Matrix3d>& map_from_image) {
  std::string text;
  char number[40];
  for (size_t i = 0; i < relative_image_paths.size(); ++i) {
    text += relative_image_paths[i] + "\n";
    if (i >= map_from_image.size()) continue;
    for (int k = 0; k < 9; ++k) {
      std::snprintf(number, sizeof(number), "%.17g", map_from_image[i](k / 3, k % 3));
      text += (k ? " " : "") + std::string(number);
    }
    text += "\n";
  }
  return text;
}

cv::Mat loadGrayImage(const std::string& path, int expected_width, int expected_height) {
  if (!fs::exists(path)) throw InputError(path + ": image not found");
  const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw InputError(path + ": image does not decode");
  if (image.cols != expected_width || image.rows != expected_height) {
    throw InputError(path + ": image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                     ", the camera configuration says " + std::to_string(expected_width) + "x" +
                     std::to_string(expected_height));
  }
  return image;
}

}  // namespace groundslam
