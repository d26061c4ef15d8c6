#include "groundslam/io/Dataset.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <optional>
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

/// The number a file name stands for ("1700000000.133.png" -> 1700000000.133), if it is one.
std::optional<double> numericName(const std::string& path) {
  const std::string stem = fs::path(path).stem().string();
  if (stem.empty() || !(std::isdigit(static_cast<unsigned char>(stem.front())) || stem.front() == '.')) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(stem.c_str(), &end);
  if (end != stem.c_str() + stem.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

bool folderHasImages(const fs::path& folder) {
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    if (entry.is_regular_file() && isImageFile(entry.path())) return true;
  }
  return false;
}

Dataset openImageFolder(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && isImageFile(entry.path())) names.push_back(entry.path().filename().string());
  }
  if (names.empty()) throw InputError(folder.string() + ": folder contains no images (png, jpg, bmp, tif, pgm)");
  std::sort(names.begin(), names.end(), naturalLess);
  // Names that are all numbers (times: 1700000000.133.png) go in numeric order, which natural order is not
  // for decimals (".2" would come before ".133").
  std::vector<std::pair<double, std::string>> numbered;  // each name parsed once
  for (const std::string& name : names) {
    if (const auto value = numericName(name)) numbered.emplace_back(*value, name);
  }
  if (numbered.size() == names.size()) {
    std::stable_sort(numbered.begin(), numbered.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (size_t i = 0; i < names.size(); ++i) names[i] = numbered[i].second;
  }
  Dataset dataset;
  dataset.source = folder.string();
  dataset.camera_yaml = cameraYamlIn(folder);
  for (size_t i = 0; i < names.size(); ++i) {
    dataset.frames.push_back({(folder / names[i]).string(), static_cast<double>(i), std::nullopt, true});
  }
  return dataset;
}

std::string lineRef(const std::string& file, int line_number) { return file + ":" + std::to_string(line_number); }

/// HD Ground's A maps image pixels to map pixels of the same size: a rotation and a translation, up to the
/// small errors of a real calibration. Anything else (all zero, huge, mirrored, projective) is not a pose.
void checkMapHomography(const Eigen::Matrix3d& A, const std::string& file, int line_number) {
  const auto bad = [&](const std::string& what) {
    throw InputError(lineRef(file, line_number) + ": pose matrix " + what +
                     " (expected a rotation and translation from image pixels to map pixels, last row 0 0 1)");
  };
  if (std::abs(A(2, 0)) > 1e-6 || std::abs(A(2, 1)) > 1e-6 || std::abs(A(2, 2) - 1.0) > 1e-6) bad("has a last row other than 0 0 1");
  if (std::abs(A(0, 2)) > 1e9 || std::abs(A(1, 2)) > 1e9) bad("has a translation beyond 1e9 map pixels");
  const Eigen::Vector2d c0 = A.block<2, 1>(0, 0), c1 = A.block<2, 1>(0, 1);
  const double det = A.block<2, 2>(0, 0).determinant();
  if (!(det > 0.0)) bad("is singular or mirrored");
  const double scale = std::sqrt(det);
  if (scale < 0.5 || scale > 2.0) bad("scales image pixels by " + std::to_string(scale) + ", not about 1");
  if (std::abs(c0.norm() - c1.norm()) > 0.1 * scale || std::abs(c0.dot(c1)) > 0.1 * scale * scale) bad("is not a rotation");
}

Eigen::Matrix3d parsePoseLine(const std::string& line, const std::string& file, int line_number) {
  const std::vector<double> v = parseNumbers(line, file, line_number);
  if (v.size() != 9) {
    throw InputError(lineRef(file, line_number) + ": expected 9 numbers (row-major 3x3 A), got " + std::to_string(v.size()));
  }
  Eigen::Matrix3d A;
  A << v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8];
  checkMapHomography(A, file, line_number);
  return A;
}

/// A pose line that starts with `*` and whitespace is unreliable; returns the rest of the line.
std::optional<std::string> unreliablePoseText(const std::string& text) {
  if (text.size() < 2 || text[0] != '*' || (text[1] != ' ' && text[1] != '\t')) return std::nullopt;
  return text.substr(2);
}

/// A `.txt` whose every line names an image file: a plain list of images (no HD Ground poses).
bool isPlainImageList(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  bool any = false;
  while (std::getline(in, line)) {
    const std::string entry = trim(line);
    if (entry.empty()) continue;
    if (!isImageFile(fs::path(entry))) return false;
    any = true;
  }
  return any;
}

Dataset openHdGroundList(const fs::path& list, bool with_poses) {
  const std::string file = list.string();
  Dataset dataset;
  dataset.source = file;
  dataset.camera_yaml = cameraYamlIn(list.parent_path());
  const std::string text = readTextFile(file);
  if (with_poses && isPlainImageList(text)) with_poses = false;  // a plain list of image paths
  for (const HdGroundListEntry& entry : parseHdGroundList(text, file, with_poses)) {
    const fs::path image = list.parent_path() / entry.image;
    std::error_code error;
    if (!fs::is_regular_file(image, error)) {
      const std::string shown = entry.image.size() > 200 ? entry.image.substr(0, 200) + "..." : image.string();
      throw InputError(lineRef(file, entry.line_number) + ": image '" + shown + "' not found" +
                       (error ? " (" + error.message() + ")" : ""));
    }
    dataset.frames.push_back({image.string(), static_cast<double>(dataset.frames.size()), entry.map_from_image,
                              entry.pose_reliable});
  }
  return dataset;
}

/// Real timestamps when the dataset has them: timestamps.txt (beside the list or folder, else in the images'
/// folder), else numeric file names; the frame index otherwise.
void assignTimestamps(Dataset& dataset, const fs::path& folder) {
  std::vector<fs::path> candidates = {folder / "timestamps.txt"};
  if (!dataset.frames.empty()) {
    const fs::path images = fs::path(dataset.frames.front().image_path).parent_path() / "timestamps.txt";
    if (images != candidates.front()) candidates.push_back(images);
  }
  for (const fs::path& candidate : candidates) {
    std::error_code error;
    if (!fs::is_regular_file(candidate, error)) continue;
    const std::string file = candidate.string();
    std::istringstream in(readTextFile(file));
    std::vector<double> times;
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      const auto first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      const std::vector<double> values = parseNumbers(line, file, number);
      if (values.size() != 1) throw InputError(lineRef(file, number) + ": expected one timestamp in seconds, got " + std::to_string(values.size()) + " numbers");
      if (!times.empty() && !(values[0] > times.back())) {
        throw InputError(lineRef(file, number) + ": timestamps must increase (" + std::to_string(values[0]) + " after " + std::to_string(times.back()) + ")");
      }
      times.push_back(values[0]);
    }
    if (times.size() != dataset.frames.size()) {
      throw InputError(file + ": " + std::to_string(times.size()) + " timestamps for " + std::to_string(dataset.frames.size()) + " images (one per image, in order)");
    }
    for (size_t i = 0; i < times.size(); ++i) dataset.frames[i].timestamp = times[i];
    dataset.timestamps_from = file;
    return;
  }
  std::vector<double> named;
  for (const DatasetFrame& frame : dataset.frames) {
    const auto value = numericName(frame.image_path);
    if (!value || (!named.empty() && !(*value > named.back()))) return;  // the index, as before
    named.push_back(*value);
  }
  // Names of 13 digits or more before any point are nanoseconds (EuRoC, ROS bag exports: 1403636579763555584.png).
  const bool nanoseconds = !named.empty() && named.front() >= 1e12;
  for (size_t i = 0; i < named.size(); ++i) dataset.frames[i].timestamp = nanoseconds ? named[i] * 1e-9 : named[i];
  dataset.timestamps_from = nanoseconds ? "file names (nanoseconds)" : "file names";
}

}  // namespace

std::vector<HdGroundListEntry> parseHdGroundList(const std::string& text, const std::string& file, bool with_poses) {
  std::istringstream in(text);
  std::vector<HdGroundListEntry> entries;
  std::string line;
  bool expect_pose = false;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line_number == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // a UTF-8 byte order mark
    const std::string text_line = trim(line);
    if (text_line.empty()) continue;
    if (expect_pose) {
      const std::optional<std::string> unreliable = unreliablePoseText(text_line);
      entries.back().map_from_image = parsePoseLine(unreliable.value_or(text_line), file, line_number);
      entries.back().pose_reliable = !unreliable;
      expect_pose = false;
      continue;
    }
    if (text_line.find('\0') != std::string::npos) throw InputError(lineRef(file, line_number) + ": image path contains a NUL byte");
    if (text_line.size() > 4096) {
      throw InputError(lineRef(file, line_number) + ": image path is " + std::to_string(text_line.size()) +
                       " characters long (at most 4096)");
    }
    entries.push_back({text_line, line_number, std::nullopt, true});
    expect_pose = with_poses;
  }
  if (expect_pose) throw InputError(lineRef(file, line_number) + ": image without a pose line");
  if (entries.empty()) throw InputError(file + ": the list names no images");
  return entries;
}

bool Dataset::hasGroundTruth() const {
  return std::any_of(frames.begin(), frames.end(), [](const DatasetFrame& f) { return f.map_from_image.has_value(); });
}

Dataset openDataset(const std::string& path) {
  const fs::path p(path);
  if (!fs::exists(p)) throw InputError(path + ": no such file or folder");
  Dataset dataset;
  const std::string ext = p.extension().string();
  if (isVideoFile(path) && !fs::is_directory(p)) {
    dataset.source = path;
    dataset.video_file = path;
    dataset.camera_yaml = cameraYamlIn(p.parent_path());
    dataset.timestamps_from = "the video's clock";
  } else if (fs::is_directory(p)) {
    // A folder that `simulate` wrote (or any folder holding one HD Ground list and no images): its list.
    std::error_code error;
    if (fs::is_regular_file(p / "sequence.txt", error) && !folderHasImages(p)) return openDataset((p / "sequence.txt").string());
    dataset = openImageFolder(p);
    assignTimestamps(dataset, p);
  } else if (ext == ".txt" || ext == ".test") {
    dataset = openHdGroundList(p, ext == ".txt");
    assignTimestamps(dataset, p.parent_path());
  } else {
    throw InputError(path + ": not a dataset: expected an HD Ground list or a list of image paths (.txt, .test), "
                     "an image folder, or a video file (.mp4, .avi, .mkv, ...)");
  }
  return dataset;
}

bool isVideoFile(const std::string& path) {
  static const std::set<std::string> extensions = {".mp4", ".avi", ".mkv", ".mov", ".webm", ".m4v", ".mjpg", ".mjpeg"};
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extensions.count(ext) > 0;
}

Dataset openCameraDevice(int device, const std::optional<std::string>& camera_yaml) {
  if (device < 0) throw InputError("--camera " + std::to_string(device) + ": a device index is 0 or more");
  Dataset dataset;
  dataset.source = "camera " + std::to_string(device);
  dataset.camera_device = device;
  dataset.camera_yaml = camera_yaml;
  dataset.timestamps_from = "the clock (seconds since the first frame)";
  return dataset;
}

void selectFrames(Dataset& dataset, long long start, long long stop, long long every) {
  const auto n = static_cast<long long>(dataset.frames.size());
  if (start < 0) throw InputError("--start " + std::to_string(start) + ": must be 0 or more");
  if (every < 1) throw InputError("--every " + std::to_string(every) + ": must be 1 or more");
  if (dataset.isVideo()) {  // applied while reading: the length of a video or a camera's stream is not known
    if (stop >= 0 && stop <= start) throw InputError(dataset.source + ": --stop " + std::to_string(stop) + " leaves no frame after --start");
    dataset.video_start = start, dataset.video_stop = stop, dataset.video_every = every;
    return;
  }
  if (stop < 0 || stop > n) stop = n;
  if (start >= stop) {
    throw InputError(dataset.source + ": --start " + std::to_string(start) + " leaves no frame (the dataset has " + std::to_string(n) +
                     (stop < n ? ", --stop " + std::to_string(stop) : std::string()) + ")");
  }
  std::vector<DatasetFrame> kept;
  for (long long i = start; i < stop; i += every) kept.push_back(dataset.frames[static_cast<size_t>(i)]);
  dataset.frames = std::move(kept);
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

Trajectory groundTruthOf(const Dataset& dataset, const CameraConfig& camera, std::optional<double> map_meters_per_pixel) {
  const double meters_per_pixel = map_meters_per_pixel.value_or(camera.mounting_height_m / camera.fx);
  Trajectory poses;
  for (const auto& frame : dataset.frames) {
    if (!frame.map_from_image || !frame.pose_reliable) continue;
    poses.push_back({frame.timestamp, robotPoseFromMapHomography(*frame.map_from_image, camera.cx,
                                                                 camera.cy, meters_per_pixel)});
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

}  // namespace groundslam
