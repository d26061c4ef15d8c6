// Right after tracking is lost for too little evidence or for the robot's speed, the next frames are measured against
// the last tracked one.
#include <optional>
#include <vector>

#include "groundslam/pipeline/Slam.hpp"
#include "groundslam/pipeline/StageTimer.hpp"

namespace groundslam {

void Slam::bridgeLoss(const Keyframe& current, const AlignmentImage& alignment, FrameResult& result) {
  const int frames_since = current.index - tracked_frame_;
  // Only a loss for too little evidence (one blurred or covered image, a patch of smooth floor) or for the robot's
  // speed (frames dropped without a trace), on a floor that does not repeat: there a motion spanning the lost frames
  // matches one repetition over as readily as the right one.
  if (!bridgeable_loss_ || repeatedFloor(current.index) || !tracked_keyframe_ || frames_since < 2 ||
      frames_since > config_.odometry_checks.bridge_max_frames) {
    return;
  }
  StageTimer timer;
  std::optional<Bridge> bridge = bridgeByFeatures(current);
  if (!bridge) bridge = bridgeByAlignment(current, alignment);
  result.times.loop_ms += timer.lap();
  if (!bridge) return;
  graph_.addEdge({tracked_frame_, current.index, bridge->T_tracked_current,
                  informationFrom(bridge->covariance, config_.graph.min_sigma_m, config_.graph.min_sigma_rad), true});
  joinMap(result);
}

std::optional<Slam::Bridge> Slam::bridgeByFeatures(const Keyframe& current) const {
  // Matched and fitted as odometry is, and believed as a loop closure would be: enough inliers, a small covariance,
  // no rival transform, and the robot's speed over the time between the two frames (unless nearly every match
  // agrees: frames dropped without a trace in the timestamps).
  const Keyframe& tracked = *tracked_keyframe_;
  const std::vector<Match> matches =
      withoutRobotArtifacts(matcher_.match(current.features.descriptors, tracked.features.descriptors), tracked, current);
  const RigidEstimate fit = fitMatches(matches, tracked, current, odometry_fitting_);
  const LoopClosureSettings& gates = config_.loop_closure;
  const OdometryChecks& checks = config_.odometry_checks;
  if (!fit.ok() || fit.inliers < gates.min_inliers || fit.covarianceScore() > gates.max_covariance_score ||
      fit.ambiguity() > checks.max_ambiguity) {
    return std::nullopt;
  }
  const bool decisive = fit.inliers >= checks.decisive_inlier_share * static_cast<double>(matches.size());
  if (!decisive && !plausibleMotion(fit.T_target_source, tracked_time_, current.timestamp)) return std::nullopt;
  return Bridge{fit.T_target_source, fit.covariance};
}

std::optional<Slam::Bridge> Slam::bridgeByAlignment(const Keyframe& current, const AlignmentImage& alignment) const {
  const OdometryChecks& checks = config_.odometry_checks;
  if (!checks.align_images || tracked_alignment_.pixels.empty() || alignment.pixels.empty()) return std::nullopt;
  const auto aligned = alignFromSteps(tracked_alignment_, alignment, current.index - tracked_frame_);
  if (!aligned) return std::nullopt;
  const Pose2 T_tracked_current = groundMotionOf(aligned->W_previous_current);
  if (!plausibleMotion(T_tracked_current, tracked_time_, current.timestamp)) return std::nullopt;
  return Bridge{T_tracked_current, sigmaCovariance(checks.align_sigma_m, checks.align_sigma_rad)};
}

}  // namespace groundslam
