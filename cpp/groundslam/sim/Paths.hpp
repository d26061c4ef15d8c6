#pragma once
// Robot paths for the simulator, sampled every `step_m` of arc length. Each path integrates a
// curvature profile exactly, so consecutive poses differ by a known SE(2) motion.

#include <cstdint>
#include <string>
#include <vector>

#include "groundslam/core/Pose2.hpp"

namespace groundslam::sim {

enum class PathKind { loop, lawnmower, random_walk };

const std::vector<std::string>& pathKindNames();
bool parsePathKind(const std::string& name, PathKind& kind);
std::string pathKindName(PathKind kind);

struct PathSettings {
  PathKind kind = PathKind::loop;
  int frames = 300;                   ///< poses to produce
  double step_m = 0.01;               ///< arc length between frames
  double max_turn_rad = 0.25;         ///< largest heading change per frame, radians (random walk)
  int laps = 2;                       ///< loop: times around
  double lane_length_m = 0.6;         ///< lawnmower: length of a lane
  double lane_spacing_m = 0.08;       ///< lawnmower: distance between lanes (less than the footprint: overlap)
  double area_m = 0.6;                ///< random walk: side of the square the robot stays in
  std::uint64_t seed = 1;             ///< random walk
};

std::vector<Pose2> generatePath(const PathSettings& settings);

}  // namespace groundslam::sim
