#pragma once
// TUM trajectory files: `t x y z qx qy qz qw`, z = qx = qy = 0, qz = sin(theta/2), qw = cos(theta/2).

#include <string>
#include <vector>

#include "groundslam/core/Trajectory.hpp"

namespace groundslam {

std::string formatTum(const std::vector<StampedPose>& poses);
void writeTum(const std::string& path, const std::vector<StampedPose>& poses);
/// Reads a TUM file; a 3-D pose is projected to the plane (yaw from the quaternion). Throws InputError.
std::vector<StampedPose> readTum(const std::string& path);
/// Parses the text of a TUM file; `source` names it in errors. Throws InputError.
std::vector<StampedPose> parseTum(const std::string& text, const std::string& source);

}  // namespace groundslam
