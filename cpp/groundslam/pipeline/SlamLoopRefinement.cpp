// Not in the paper: a loop's transform measured on its keypoint pairs tracked into the place's image, and measured
// again at the end of the run through the frames' final mounts.
//
// ORB keypoints scatter by most of a pixel about the ground point they stand for, and a loop's fit rests on a few
// dozen to a few hundred of them: its heading was off by 0.05-0.4 degrees (standard deviation, the fewer inliers the
// more), where the images agree to a few hundredths of a pixel (core/PointTracking.hpp). What is left is the
// frames' tilt: while the run goes, a frame's ground points are projected through its mount as estimated then (off
// by 0.35-0.48 degrees on the standard matrix), the smoothed mounts at the end are off by 0.11-0.21. The end
// corrects each pose for its own frame's mount, which is right for a step between frames that see the same ground
// but not for a loop whose two images share only a part of it: there a tilt turns the transform (a few hundredths
// of a degree per tenth of a degree of tilt). So each loop keeps the rays of its pairs and is fitted again.
#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>

#include "groundslam/pipeline/Slam.hpp"

namespace groundslam {

void Slam::keepPlaceTracking(int frame, const TrackingImage& tracking) {
  if (!loop_closer_ || !config_.loop_closure.refine_by_tracked_points || tracking.pixels.empty()) return;
  place_tracking_[frame] = tracking;  // shares the pixels: neither is changed
  pending_place_tracking_.push_back(frame);
  // A frame is admitted as a place, or left out, k frames later (the database's delay).
  const int decided = frame - config_.loop_closure.database_delay_frames - 1;
  while (!pending_place_tracking_.empty() && pending_place_tracking_.front() <= decided) {
    if (loop_closer_->places().find(pending_place_tracking_.front()) == nullptr) place_tracking_.erase(pending_place_tracking_.front());
    pending_place_tracking_.pop_front();
  }
}

Slam::LoopRays Slam::guidedLoopPairs(const LoopCandidate& loop, const Keyframe& current, const GroundFeatures& reference,
                                     const Pose2& T_a_b) const {
  const std::vector<Match> matches =
      matchNearby(current.features, reference, T_a_b, config_.outdoor.reference_match_radius_m, config_.matching.ratio);
  LoopRays keypoints{0, loop.frame_a, loop.frame_b, {}, {}};
  for (const Match& m : matches) {
    keypoints.a_rays.push_back(reference.rays[static_cast<size_t>(m.train)]);
    keypoints.b_rays.push_back(current.features.rays[static_cast<size_t>(m.query)]);
  }
  return keypoints;
}

Slam::LoopRays Slam::predictedLoopPairs(const LoopCandidate& loop, const Keyframe& current, const Pose2& T_a_b) const {
  // An even sample of the current keypoints, each paired with the ray where T_a_b puts its ground point in the
  // place's image (through the place's mount as used): a warp known to a pixel or so, for the tracker.
  const Eigen::Isometry3d camera_a = mountFor(calibrated_mount_, used_mounts_[static_cast<size_t>(loop.frame_a)]).inverse();
  const CameraIntrinsics& k = camera_.intrinsics();
  const double margin = point_tracking_.window_px;
  LoopRays pairs{0, loop.frame_a, loop.frame_b, {}, {}};
  const size_t count = std::min(kRescuePairs, current.features.size());
  for (size_t n = 0; n < count; ++n) {
    const size_t i = n * current.features.size() / count;
    const Eigen::Vector2d p = T_a_b * current.features.points[i];
    const Eigen::Vector3d c = camera_a * Eigen::Vector3d(p.x(), p.y(), 0.0);
    if (c.z() <= 0.0) continue;
    const Eigen::Vector2d ray(c.x() / c.z(), c.y() / c.z());
    const auto pixel = pixelOfRay(ray);
    if (!pixel || pixel->x < margin || pixel->y < margin || pixel->x > k.width - margin || pixel->y > k.height - margin) continue;
    pairs.a_rays.push_back(ray);
    pairs.b_rays.push_back(current.features.rays[i]);
  }
  return pairs;
}

std::optional<Slam::LoopRays> Slam::trackLoopPairs(const LoopRays& keypoints, const TrackingImage& tracking) const {
  const auto image = place_tracking_.find(keypoints.frame_a);
  if (!config_.loop_closure.refine_by_tracked_points || tracking.pixels.empty() || image == place_tracking_.end()) return std::nullopt;
  // The warp of the current image onto the place's that the pairs make, and each current keypoint tracked from it.
  std::vector<cv::Point2d> current_px, reference_px;
  std::vector<size_t> pair_of;
  for (size_t i = 0; i < keypoints.a_rays.size(); ++i) {
    const auto c = pixelOfRay(keypoints.b_rays[i]);
    const auto r = pixelOfRay(keypoints.a_rays[i]);
    if (!c || !r) continue;
    current_px.push_back(*c);
    reference_px.push_back(*r);
    pair_of.push_back(i);
  }
  const size_t min_points = static_cast<size_t>(std::max(4, point_tracking_.min_points));
  if (current_px.size() < min_points) return std::nullopt;
  constexpr double kWarpInlierPx = 3.0;  // keypoints scatter by most of a pixel; the tracker finds the rest
  const cv::Mat H = cv::findHomography(current_px, reference_px, cv::RANSAC, kWarpInlierPx);
  if (H.empty()) return std::nullopt;
  const std::vector<std::optional<cv::Point2d>> tracked = trackPoints(image->second, tracking, current_px, cv::Matx33d(H), point_tracking_);
  LoopRays tracked_pairs{0, keypoints.frame_a, keypoints.frame_b, {}, {}};
  std::vector<Eigen::Vector2d> tracked_px;
  for (size_t i = 0; i < tracked.size(); ++i) {
    if (!tracked[i]) continue;
    tracked_px.emplace_back(tracked[i]->x, tracked[i]->y);
    tracked_pairs.b_rays.push_back(keypoints.b_rays[pair_of[i]]);
  }
  if (tracked_px.size() < min_points) return std::nullopt;
  tracked_pairs.a_rays = camera_.normalisedRays(tracked_px);
  return tracked_pairs;
}

std::optional<Slam::LoopRays> Slam::measureLoopPairs(LoopCandidate& loop, const Keyframe& current, const TrackingImage& tracking) const {
  const Place* place = loop_closer_->places().find(loop.frame_a);
  if (place == nullptr || static_cast<size_t>(loop.frame_a) >= used_mounts_.size() || !current.features.hasRays()) return std::nullopt;
  const GroundFeatures reference = place->features();
  if (!reference.hasRays()) return std::nullopt;
  // Guided pairs around the loop's transform: the keypoints' pairs, kept when the images cannot do better.
  const LoopRays keypoints = guidedLoopPairs(loop, current, reference, loop.T_a_b);
  const std::optional<LoopRays> tracked_pairs = trackLoopPairs(keypoints, tracking);
  if (!tracked_pairs) return keypoints;
  // The tracked points on the ground as the loop's own points were put there: through the mounts used then.
  const auto fit = fitLoopRays(*tracked_pairs, used_mounts_[static_cast<size_t>(loop.frame_a)], current.mount, loop.T_a_b);
  if (!fit) return keypoints;
  // The refit must agree with the keypoints' fit within what that fit allows (three standard deviations): else the
  // tracked points are not the loop's ground (a look-alike, something still in the image) and the keypoints stand.
  const Pose2 change = loop.T_a_b.inverse() * fit->T_target_source;
  const double allowed_m = 3.0 * std::sqrt(std::max(loop.covariance(0, 0), loop.covariance(1, 1))) + config_.graph.min_sigma_m;
  const double allowed_rad = 3.0 * std::sqrt(loop.covariance(2, 2)) + config_.graph.min_sigma_rad;
  if (change.translation().norm() > allowed_m || std::abs(change.theta) > allowed_rad) return keypoints;
  loop.T_a_b = fit->T_target_source;
  loop.covariance = fit->covariance;
  return tracked_pairs;
}

std::optional<Slam::LoopRays> Slam::rescueLoop(LoopCandidate& loop, const Keyframe& current, const TrackingImage& tracking) const {
  if (!loop.coarse_T_a_b || floor_looks_repeated_) return std::nullopt;  // on a repeating floor a weak consensus may be a repetition
  if (static_cast<size_t>(loop.frame_a) >= used_mounts_.size() || !current.features.hasRays()) return std::nullopt;
  const Pose2& coarse = *loop.coarse_T_a_b;
  const std::optional<LoopRays> tracked_pairs = trackLoopPairs(predictedLoopPairs(loop, current, coarse), tracking);
  if (!tracked_pairs) return std::nullopt;
  const auto fit = fitLoopRays(*tracked_pairs, used_mounts_[static_cast<size_t>(loop.frame_a)], current.mount, coarse);
  // Gate 3 on the tracked points, and the transform the keypoints agreed on within their matching radius: points
  // tracked to somewhere else slid off a look-alike.
  const LoopClosureSettings& gates = config_.loop_closure;
  if (!fit || fit->inliers < gates.min_inliers || fit->covarianceScore() > gates.max_covariance_score) return std::nullopt;
  const Pose2 change = coarse.inverse() * fit->T_target_source;
  if (change.translation().norm() > config_.outdoor.reference_match_radius_m || std::abs(change.theta) > kRescueAgreementRad) return std::nullopt;
  loop.T_a_b = fit->T_target_source;
  loop.covariance = fit->covariance;
  // How far it moves the current frame from the map's estimate (the failed fit's figure was of no transform).
  const std::vector<Pose2>& poses = graph_.poses();
  const Pose2 estimated = between(poses[static_cast<size_t>(loop.frame_a)], poses[static_cast<size_t>(loop.frame_b)]);
  loop.correction_m = (loop.T_a_b.translation() - estimated.translation()).norm();
  loop.inliers = fit->inliers;
  loop.covariance_score = fit->covarianceScore();
  loop.rejected_by = LoopGate::none;
  return tracked_pairs;
}

GroundFeatures Slam::projectRays(const std::vector<Eigen::Vector2d>& rays, const MountState& mount) const {
  GroundFeatures features;
  features.rays = rays;
  features.points.assign(rays.size(), Eigen::Vector2d::Zero());
  reprojectToGround(features, mountFor(calibrated_mount_, mount));
  return features;
}

RigidEstimate Slam::fitRays(const LoopRays& pairs, const MountState& a_mount, const MountState& b_mount, const Pose2& T_guess) const {
  return refineRigidTransform(projectRays(pairs.a_rays, a_mount).points, projectRays(pairs.b_rays, b_mount).points, T_guess,
                              odometry_fitting_);
}

std::optional<RigidEstimate> Slam::fitLoopRays(const LoopRays& pairs, const MountState& a_mount, const MountState& b_mount,
                                               const Pose2& T_guess) const {
  const GroundFeatures a = projectRays(pairs.a_rays, a_mount);
  const GroundFeatures b = projectRays(pairs.b_rays, b_mount);
  RigidEstimate fit = refineRigidTransform(a.points, b.points, T_guess, odometry_fitting_);
  if (!fit.ok()) return std::nullopt;
  fit.covariance += mountCovariance(fit.T_target_source, a, a_mount, b, b_mount);
  return fit;
}

Eigen::Matrix3d Slam::mountCovariance(const Pose2& T_a_b, const GroundFeatures& a_points, const MountState& a_mount,
                                      const GroundFeatures& b_points, const MountState& b_mount) const {
  // Each frame's tilt is an estimate, off by about loop_closure.tilt_sigma_deg; a fit of one pair of views cannot
  // tell (its residuals do not show it), yet it turns and shifts the pair's transform. Its effect, frame by frame
  // and axis by axis: the points re-projected with the tilt off by that much, and the transform fitted again.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  const double sigma = config_.loop_closure.tilt_sigma_deg * M_PI / 180.0;
  if (!(sigma > 0.0)) return covariance;
  for (int side = 0; side < 2; ++side) {
    for (int axis = 0; axis < 2; ++axis) {
      MountState mount = side == 0 ? a_mount : b_mount;
      (axis == 0 ? mount.roll_rad : mount.pitch_rad) += sigma;
      GroundFeatures moved = side == 0 ? a_points : b_points;
      reprojectToGround(moved, mountFor(calibrated_mount_, mount));
      const RigidEstimate fit = side == 0 ? refineRigidTransform(moved.points, b_points.points, T_a_b, odometry_fitting_)
                                          : refineRigidTransform(a_points.points, moved.points, T_a_b, odometry_fitting_);
      if (!fit.ok()) continue;
      const Eigen::Vector3d change(fit.T_target_source.x - T_a_b.x, fit.T_target_source.y - T_a_b.y,
                                   std::remainder(fit.T_target_source.theta - T_a_b.theta, 2.0 * M_PI));
      covariance += change * change.transpose();
    }
  }
  return covariance;
}

bool Slam::remeasureLoops() {
  if (!config_.loop_closure.remeasure_at_end || mount_corrections_.empty() || loop_rays_.empty()) return false;
  // The graph's poses are those of the mounts used during the run; pose i with its final mount is pose i *
  // mount_corrections_[i]. A loop's pairs fitted through the final mounts, brought back to the graph's poses, and
  // through the mounts used: the edge takes the change between the two, what the mounts alone make. Not the final
  // fit itself: where the keypoints' guided pairs stood for a loop (its points did not track), their own fit is not
  // the loop's transform, and may lie a degree from it (measured on a standard asphalt random walk: 1.6 degrees,
  // turning a loop right within 0.2 degrees 1.8 degrees off).
  for (const LoopRays& pairs : loop_rays_) {
    const size_t a = static_cast<size_t>(pairs.frame_a), b = static_cast<size_t>(pairs.frame_b);
    if (a >= mount_corrections_.size() || b >= mount_corrections_.size() || a >= used_mounts_.size() || b >= used_mounts_.size()) continue;
    const GraphEdge& edge = graph_.edges()[pairs.edge];
    // Both fits start from one transform, the pairs' own fit through the mounts used: where the pairs fit two
    // transforms almost as well, fits started apart can end apart, and the difference is not the mounts' (measured on
    // a grass lawnmower outdoors: a loop turned 1.05 degrees, to 2.3 degrees off).
    const RigidEstimate as_used = fitRays(pairs, used_mounts_[a], used_mounts_[b], edge.T_from_to);
    if (!as_used.ok()) continue;
    const Pose2 guess = mount_corrections_[a].inverse() * as_used.T_target_source * mount_corrections_[b];
    const auto fit = fitLoopRays(pairs, final_mounts_[a], final_mounts_[b], guess);
    if (!fit) continue;
    const Pose2 by_the_mounts = as_used.T_target_source.inverse() * mount_corrections_[a] * fit->T_target_source * mount_corrections_[b].inverse();
    graph_.remeasureEdge(pairs.edge, edge.T_from_to * by_the_mounts,
                         informationFrom(fit->covariance, config_.graph.min_sigma_m, config_.graph.min_sigma_rad));
  }
  return true;
}

}  // namespace groundslam
