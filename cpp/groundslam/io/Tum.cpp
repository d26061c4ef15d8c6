#include "groundslam/io/Tum.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/TextParsing.hpp"

namespace groundslam {

std::string formatTum(const std::vector<StampedPose>& poses) {
  std::string text;
  char line[256];
  for (const auto& p : poses) {
    const double half = 0.5 * p.T_world_robot.theta;
    std::snprintf(line, sizeof(line), "%.9f %.12f %.12f 0 0 0 %.12f %.12f\n", p.timestamp, p.T_world_robot.x,
                  p.T_world_robot.y, std::sin(half), std::cos(half));
    text += line;
  }
  return text;
}

void writeTum(const std::string& path, const std::vector<StampedPose>& poses) {
  writeFileAtomically(path, formatTum(poses));
}

std::vector<StampedPose> readTum(const std::string& path) { return parseTum(readTextFile(path), path); }

std::vector<StampedPose> parseTum(const std::string& text, const std::string& path) {
  std::istringstream in(text);
  std::vector<StampedPose> poses;
  std::string line;
  for (int line_number = 1; std::getline(in, line); ++line_number) {
    const std::string trimmed = trim(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const std::vector<double> v = parseNumbers(trimmed, path, line_number);
    if (v.size() != 8) {
      throw InputError(path + ":" + std::to_string(line_number) + ": expected 8 numbers (t x y z qx qy qz qw), got " +
                       std::to_string(v.size()));
    }
    // Yaw of the quaternion (qx, qy, qz, qw) = (v[4], v[5], v[6], v[7]).
    const double yaw = std::atan2(2.0 * (v[7] * v[6] + v[4] * v[5]), 1.0 - 2.0 * (v[5] * v[5] + v[6] * v[6]));
    poses.push_back({v[0], Pose2(v[1], v[2], yaw)});
  }
  return poses;
}

}  // namespace groundslam
