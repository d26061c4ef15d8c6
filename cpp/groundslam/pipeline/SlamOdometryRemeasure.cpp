// Not in the paper: each odometry step fitted again at the end of the run through its two frames' final mounts.
//
// A frame's ground points are projected through its mount as estimated during the run; a tilt off sideways by e
// (roll, for a robot moving along its x axis) stretches the image's far side against its near side, so that ground
// points a step t apart shift apart by t * e * y / h at lateral offset y and height h: the fitted step turns by about
// t * e / h (a 1 cm step, 25 cm height, 0.1 degrees of roll error: 0.004 degrees). Unlike a shift, that turn does
// not cancel between consecutive steps; the run's mount errors change slowly, so it adds up along the path (measured
// on the standard carpet lawnmower, seed 307: -0.9 degrees of heading over 360 steps with the mount rocking 0.5
// degrees, -0.1 with it still). The per-frame correction of the trajectory (mount_corrections_) moves each pose for
// its own mount and cannot undo a turn that depends on the step. So each step keeps a sample of its pairs' rays, and
// at the end the change of their fit from the mounts used to the final ones (solved over the run, about twice as
// precise) is applied to the step's edge, which keeps the heading the images refined.
#include <algorithm>

#include "groundslam/pipeline/Slam.hpp"

namespace groundslam {

void Slam::keepOdometryPairs(const OdometryEdge& odometry, const Keyframe& previous, const Keyframe& current) {
  if (!config_.outdoor.remeasure_odometry || !config_.outdoor.estimate_mount || !config_.outdoor.smooth_mount || odometry.aligned ||
      odometry.used.empty() || !previous.features.hasRays() || !current.features.hasRays()) {
    return;
  }
  LoopRays pairs{graph_.edges().size() - 1, previous.index, current.index, {}, {}};
  // An even sample over the inliers: their spread over the image, which the turn depends on, is kept.
  const size_t count = std::min(kRemeasuredPairs, odometry.used.size());
  for (size_t k = 0; k < count; ++k) {
    const Match& m = odometry.used[k * odometry.used.size() / count];
    pairs.a_rays.push_back(previous.features.rays[static_cast<size_t>(m.train)]);
    pairs.b_rays.push_back(current.features.rays[static_cast<size_t>(m.query)]);
  }
  odometry_rays_.push_back(std::move(pairs));
}

bool Slam::remeasureOdometry() {
  if (odometry_rays_.empty() || mount_corrections_.empty()) return false;
  for (const LoopRays& pairs : odometry_rays_) {
    const size_t a = static_cast<size_t>(pairs.frame_a), b = static_cast<size_t>(pairs.frame_b);
    if (b >= mount_corrections_.size() || b >= final_mounts_.size() || b >= used_mounts_.size()) continue;
    const GraphEdge& edge = graph_.edges()[pairs.edge];
    const RigidEstimate used = fitRays(pairs, used_mounts_[a], used_mounts_[b], edge.T_from_to);
    if (!used.ok()) continue;
    const RigidEstimate final = fitRays(pairs, final_mounts_[a], final_mounts_[b], used.T_target_source);
    if (!final.ok()) continue;
    // The step between the frames' robot poses under their final mounts; the graph's poses are those under the
    // mounts used (pose * mount_corrections_ = pose under the final mount), as for a loop (remeasureLoops).
    const Pose2 step = edge.T_from_to * used.T_target_source.inverse() * final.T_target_source;
    remeasured_odometry_[pairs.frame_b] = step;
    graph_.remeasureEdge(pairs.edge, mount_corrections_[a] * step * mount_corrections_[b].inverse(), edge.information);
  }
  return true;
}

}  // namespace groundslam
