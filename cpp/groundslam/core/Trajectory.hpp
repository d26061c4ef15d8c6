#pragma once
#include <vector>

#include "groundslam/core/Pose2.hpp"

namespace groundslam {

struct StampedPose {
  double timestamp = 0.0;  ///< seconds, or the frame index when the data has no time
  Pose2 T_world_robot;
  bool measured = true;    ///< false when odometry failed and the pose was assumed from earlier motion
};

using Trajectory = std::vector<StampedPose>;

}  // namespace groundslam
