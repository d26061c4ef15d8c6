// Not in the paper: each odometry step fitted again at the end of the run through its two frames' final mounts.
//
// A frame's ground points are projected through its mount as estimated during the run; a tilt off sideways by e
// (roll, for a robot moving along its x axis) stretches the image's far side against its near side, so that ground
// points a step t apart shift apart by t * e * y / h at lateral offset y and height h: the fitted step turns by about
// t * e / h (a 1 cm step, 25 cm height, 0.1 degrees of roll error: 0.004 degrees). Unlike a shift, that turn does
// not cancel between consecutive steps; the run's mount errors change slowly, so it adds up along the path (measured
// on a simulated asphalt loop rocking by 0.5 degrees: the heading 25 steps add up to, 0.047 degrees RMS through the
// mounts used, 0.031 after this). The per-frame correction of the trajectory (mount_corrections_) moves each pose for
// its own mount and cannot undo a turn that depends on the step. So each step keeps a sample of its pairs' rays, and
// at the end the turn between their fits through the mounts used and through the final ones (solved over the run,
// about twice as precise in tilt), beyond what the poses' corrections explain, is applied to the step's edge, which
// keeps the heading the images refined.
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
    // The graph's poses are those under the mounts used (pose * mount_corrections_ = pose under the final mount), as
    // for a loop (remeasureLoops): the step under the final mounts is the edge corrected at both ends, and what the
    // corrections leave of the refit's change is the turn. Only the turn is taken: the refit's translation follows
    // the final heights too, which are no better than the ones used (measured on a rocking loop bouncing by 2 mm:
    // ATE 0.61 -> 1.50 mm with the whole change, its heading 0.017 -> 0.012 degrees).
    const Pose2& corr_a = mount_corrections_[a];
    const Pose2& corr_b = mount_corrections_[b];
    const Pose2 corrected = corr_a.inverse() * edge.T_from_to * corr_b;
    const double turn = ((corr_a.inverse() * used.T_target_source * corr_b).inverse() * final.T_target_source).theta;
    // About the pairs' centroid in the later frame, where the fit is surest.
    const GroundFeatures later = projectRays(pairs.b_rays, final_mounts_[b]);
    Eigen::Vector2d pivot = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& p : later.points) pivot += p;
    pivot /= static_cast<double>(later.points.size());
    const Pose2 turned(0.0, 0.0, turn);
    const Eigen::Vector2d shift = pivot - turned.rotation() * pivot;
    const Pose2 step = corrected * Pose2(shift.x(), shift.y(), turn);
    remeasured_odometry_[pairs.frame_b] = step;
    graph_.remeasureEdge(pairs.edge, corr_a * step * corr_b.inverse(), edge.information);
  }
  return true;
}

}  // namespace groundslam
