// Not in the paper: the camera's roll, pitch and height per frame (see core/MountEstimation.hpp), the part
// of Slam that estimates them and projects the frame's keypoints with them.
#include <algorithm>
#include <cmath>

#include "groundslam/pipeline/Slam.hpp"
#include "groundslam/pipeline/StageTimer.hpp"

#include <opencv2/calib3d.hpp>

namespace groundslam {
namespace {

/// One reference's pairs as the mount estimate takes them: the rays of both sides.
MountObservation observationOf(const GroundFeatures& reference, const MountState& reference_mount, const GroundFeatures& current,
                               const std::vector<Match>& pairs, const Pose2& T_reference_current) {
  MountObservation o;
  o.reference = reference_mount;
  o.T_guess = T_reference_current;
  for (const Match& m : pairs) {
    o.reference_rays.push_back(reference.rays[static_cast<size_t>(m.train)]);
    o.current_rays.push_back(current.rays[static_cast<size_t>(m.query)]);
  }
  return o;
}

}  // namespace

std::vector<Match> Slam::mountPairs(const std::vector<Match>& matches, const GroundFeatures& current, const GroundFeatures& reference,
                                    const Pose2& T_reference_current) const {
  std::vector<Match> pairs;
  const double inlier2 = mount_pair_radius_m_ * mount_pair_radius_m_;
  const Eigen::Matrix2d R = T_reference_current.rotation();  // once, not per match
  for (const Match& m : matches) {
    const Eigen::Vector2d& q = current.points[static_cast<size_t>(m.query)];
    if ((R * q + T_reference_current.translation() - reference.points[static_cast<size_t>(m.train)]).squaredNorm() <= inlier2) {
      pairs.push_back(m);
    }
  }
  return pairs;
}

std::optional<Slam::MountReference> Slam::farReference(const Keyframe& current, const OdometryEdge& odometry) const {
  if (recent_.size() < 2) return std::nullopt;
  const Pose2 T_world_current = graph_.poses().back() * odometry.T_prev_curr;
  for (const Keyframe& candidate : recent_) {
    if (&candidate == &recent_.back()) break;  // the previous frame: odometry already matched it
    const Pose2 predicted = between(graph_.poses()[static_cast<size_t>(candidate.index)], T_world_current);
    if (predicted.translation().norm() > mount_baseline_m_) continue;
    const std::vector<Match> matches =
        matchNearby(current.features, candidate.features, predicted, config_.outdoor.reference_match_radius_m, config_.matching.ratio);
    // Guided matches around the odometry's prediction, which is right to a fraction of a millimetre over so
    // short a baseline: refined from it, no RANSAC.
    const RigidEstimate fit = refineMatches(matches, candidate, current, predicted);
    if (!fit.ok()) return std::nullopt;
    return MountReference{&candidate, mountPairs(matches, current.features, candidate.features, fit.T_target_source), fit.T_target_source};
  }
  return std::nullopt;
}

MountEstimationSettings Slam::mountSettings() const {
  MountEstimationSettings settings;
  settings.tilt_prior_rad = config_.outdoor.tilt_prior_deg * M_PI / 180.0;
  settings.height_prior_m = config_.outdoor.height_prior_m;
  settings.reference_sigma_rad = config_.outdoor.reference_sigma_deg * M_PI / 180.0;
  settings.point_sigma_m = config_.outdoor.point_sigma_px * ground_sample_m_;
  settings.max_pairs = config_.outdoor.max_pairs;
  return settings;
}

void Slam::keepMountFactor(const MountEstimate& estimate, const std::vector<int>& frames, bool chooses_priors) {
  if (estimate.factor.information.size() == 0) return;
  // frames: the current frame, then one per observation the estimate was given.
  FrameMountFactor factor{{frames.front()}, estimate.factor, chooses_priors};
  // The estimate's own variance understates its error (see variance_inflation): so does its factor's information.
  factor.factor.information /= config_.outdoor.variance_inflation;
  factor.factor.gradient /= config_.outdoor.variance_inflation;
  for (int k : estimate.factor.observations) factor.frames.push_back(frames[static_cast<size_t>(k) + 1]);
  mount_factors_.push_back(std::move(factor));
}

void Slam::addLoopMountFactor(const LoopCandidate& loop, const Keyframe& current) {
  const Place* place = loop_closer_->places().find(loop.frame_a);
  if (place == nullptr || static_cast<size_t>(loop.frame_a) >= used_mounts_.size() || !current.features.hasRays()) return;
  const GroundFeatures reference = place->features();
  if (!reference.hasRays()) return;
  // The loop's own transform is right to a fraction of a millimetre: guided matches around it, refined, and
  // the pairs that agree with the refinement, as for a far reference.
  const std::vector<Match> matches =
      matchNearby(current.features, reference, loop.T_a_b, config_.outdoor.reference_match_radius_m, config_.matching.ratio);
  std::vector<Eigen::Vector2d> reference_points, current_points;
  for (const Match& m : matches) {
    reference_points.push_back(reference.points[static_cast<size_t>(m.train)]);
    current_points.push_back(current.features.points[static_cast<size_t>(m.query)]);
  }
  const RigidEstimate fit = refineRigidTransform(reference_points, current_points, loop.T_a_b, odometry_fitting_);
  if (!fit.ok()) return;
  const MountObservation o = observationOf(reference, used_mounts_[static_cast<size_t>(loop.frame_a)], current.features,
                                           mountPairs(matches, current.features, reference, fit.T_target_source), fit.T_target_source);
  const MountEstimate estimate = estimateMount({o}, calibrated_mount_, mountSettings());
  if (estimate.ok) keepMountFactor(estimate, {current.index, loop.frame_a}, false);
}

double Slam::Spread::keep(double square, double variance, int count) {
  const double rate = 1.0 / std::min(count, 50);  // a plain mean at first, then the last 50 or so frames
  square_mean += rate * (square - square_mean);
  variance_mean += rate * (variance - variance_mean);
  return square_mean > 0.0 ? std::max(0.0, square_mean - variance_mean) / square_mean : 0.0;
}

std::optional<cv::Point2d> Slam::pixelOfRay(const Eigen::Vector2d& ray) const {
  // The ray seen through the calibrated mount: the pixel it came from.
  const auto ground = CameraModel::intersectGround(ray, camera_.T_robot_camera());
  const auto pixel = ground ? camera_.groundToPixel(*ground) : std::nullopt;
  if (!pixel) return std::nullopt;
  return cv::Point2d(pixel->x(), pixel->y());
}

std::optional<MountObservation> Slam::trackedObservation(const Keyframe& previous, const Keyframe& current, const std::vector<Match>& pairs,
                                                        const Pose2& T_previous_current, const TrackingImage& tracking) const {
  if (tracking.pixels.empty() || previous_tracking_.pixels.empty() || pairs.size() < 4) return std::nullopt;
  // The keypoints' pixels, and the warp their matches make.
  std::vector<cv::Point2d> current_px, previous_px;
  std::vector<Match> kept;
  // No more points than the estimate takes (outdoor.max_pairs), spread over the pairs as it would spread them.
  const size_t step = (pairs.size() + static_cast<size_t>(std::max(1, config_.outdoor.max_pairs)) - 1) /
                      static_cast<size_t>(std::max(1, config_.outdoor.max_pairs));
  for (size_t i = 0; i < pairs.size(); i += std::max<size_t>(1, step)) {
    const Match& m = pairs[i];
    const auto c = pixelOfRay(current.features.rays[static_cast<size_t>(m.query)]);
    const auto p = pixelOfRay(previous.features.rays[static_cast<size_t>(m.train)]);
    if (!c || !p) continue;
    current_px.push_back(*c);
    previous_px.push_back(*p);
    kept.push_back(m);
  }
  if (kept.size() < 4) return std::nullopt;
  const cv::Mat H = cv::findHomography(current_px, previous_px, 0);
  if (H.empty()) return std::nullopt;
  const std::vector<std::optional<cv::Point2d>> tracked =
      trackPoints(previous_tracking_, tracking, current_px, cv::Matx33d(H), point_tracking_);
  MountObservation o;
  o.reference = previous.mount;
  o.T_guess = T_previous_current;
  o.point_sigma_m = config_.outdoor.track_sigma_px * tracking.scale * ground_sample_m_;
  std::vector<Eigen::Vector2d> tracked_px;
  for (size_t i = 0; i < tracked.size(); ++i) {
    if (!tracked[i]) continue;
    tracked_px.emplace_back(tracked[i]->x, tracked[i]->y);
    o.current_rays.push_back(current.features.rays[static_cast<size_t>(kept[i].query)]);
  }
  if (tracked_px.empty()) return std::nullopt;
  o.reference_rays = camera_.normalisedRays(tracked_px);
  return o;
}

void Slam::estimateMountOf(const Keyframe& previous, Keyframe& current, OdometryEdge& odometry, const TrackingImage& tracking,
                           FrameResult& result) {
  if (!previous.features.hasRays() || !current.features.hasRays()) return;
  StageTimer timer;
  // The previous frame and, when there is one, a frame farther back: the tilt shows better over a baseline.
  std::vector<MountReference> references;
  if (auto far = farReference(current, odometry)) references.push_back(std::move(*far));
  references.push_back({&previous, mountPairs(odometry.used, current.features, previous.features, odometry.T_prev_curr), odometry.T_prev_curr});
  std::vector<MountObservation> observations;
  std::vector<int> observed_frames = {current.index};
  for (const MountReference& reference : references) {
    if (!reference.keyframe->features.hasRays()) continue;
    observed_frames.push_back(reference.keyframe->index);
    std::optional<MountObservation> tracked;
    if (reference.keyframe == &previous) tracked = trackedObservation(previous, current, reference.matches, reference.T_reference_current, tracking);
    observations.push_back(tracked ? std::move(*tracked)
                                   : observationOf(reference.keyframe->features, reference.keyframe->mount, current.features,
                                                   reference.matches, reference.T_reference_current));
  }
  const MountEstimate estimate = estimateMount(observations, calibrated_mount_, mountSettings());
  if (!estimate.ok) return;
  keepMountFactor(estimate, observed_frames, true);
  // Empirical Bayes: the estimate is shrunk toward the calibrated mount by the share of the estimates' spread
  // that is noise (hardly shrunk on a rocking mount with a clear view, all the way on a rigid one).
  const MountState& e = estimate.current;
  const double calibrated_height = calibrated_mount_.translation().z();
  ++mount_estimates_;
  const double keep_tilt = tilt_spread_.keep(0.5 * (e.roll_rad * e.roll_rad + e.pitch_rad * e.pitch_rad),
                                             config_.outdoor.variance_inflation * 0.5 * estimate.tilt_covariance.trace(), mount_estimates_);
  const double keep_height = height_spread_.keep((e.height_m - calibrated_height) * (e.height_m - calibrated_height),
                                                 config_.outdoor.variance_inflation * estimate.height_variance, mount_estimates_);
  Keyframe reprojected = current;
  reprojected.mount = {keep_tilt * e.roll_rad, keep_tilt * e.pitch_rad,
                       calibrated_height + (1.0 - config_.outdoor.height_return) * keep_height * (e.height_m - calibrated_height)};
  reprojectToGround(reprojected.features, mountFor(calibrated_mount_, reprojected.mount));
  // The same matches, now between points projected with each frame's own mount. The re-projection moved the
  // current points by up to a few millimetres (height x tilt), a shift the refinement must start from: the fit
  // before re-projection, carried over by the transform that takes the new points onto the old ones.
  std::vector<Eigen::Vector2d> before, after;
  for (const Match& m : odometry.used) {
    before.push_back(current.features.points[static_cast<size_t>(m.query)]);
    after.push_back(reprojected.features.points[static_cast<size_t>(m.query)]);
  }
  const RigidEstimate fit = refineMatches(odometry.used, previous, reprojected, odometry.T_prev_curr * leastSquaresRigid(before, after));
  result.times.fit_ms += timer.lap();
  // A right mount brings the matched points closer together; one that does not is not used.
  if (!fit.ok() || fit.rms_residual_m >= odometry.rms_residual_m) return;
  current = std::move(reprojected);
  odometry.T_prev_curr = fit.T_target_source;
  odometry.covariance = fit.covariance;
  odometry.inliers = fit.inliers;
  result.inliers = fit.inliers;
  result.mount_estimated = true;
}

void Slam::smoothMount() {
  const int frames = static_cast<int>(used_mounts_.size());
  mount_corrections_.clear();
  final_mounts_.clear();
  mount_rocking_.reset();
  if (mount_factors_.empty()) return;
  MountSmoothingSettings settings;
  settings.nominal_height_m = calibrated_mount_.translation().z();
  settings.max_tilt_sigma_rad = config_.outdoor.tilt_prior_deg * M_PI / 180.0;
  settings.max_height_sigma_m = config_.outdoor.height_prior_m;
  settings.robust_outlier_z = config_.outdoor.mount_outlier_z;
  const MountSmoothing smoothing = smoothMounts(frames, mount_factors_, settings, rocking_steps_);
  if (smoothing.states.size() != static_cast<size_t>(frames)) return;
  mount_rocking_ = smoothing.rocking;
  if (!smoothing.plausible) return;  // only the widest tilt prior explains the estimates (MountSmoothing::plausible)
  // The correction moves each pose so that the ground its image shows, projected with the final mount, lands
  // where the graph put it with the mount the frame was processed with.
  const CameraIntrinsics& k = camera_.intrinsics();
  std::vector<Eigen::Vector2d> grid;
  for (int row = 1; row <= 4; ++row) {
    for (int col = 1; col <= 4; ++col) grid.emplace_back(k.width * col / 5.0, k.height * row / 5.0);
  }
  const std::vector<Eigen::Vector2d> rays = camera_.normalisedRays(grid);
  final_mounts_ = used_mounts_;  // a prior map's keyframes keep theirs
  mount_corrections_.assign(static_cast<size_t>(frames), Pose2());
  for (size_t i = static_cast<size_t>(prior_frames_); i < static_cast<size_t>(frames); ++i) {
    final_mounts_[i] = smoothing.states[i];
    const Eigen::Isometry3d used = mountFor(calibrated_mount_, used_mounts_[i]), smoothed = mountFor(calibrated_mount_, final_mounts_[i]);
    std::vector<Eigen::Vector2d> from_used, from_smoothed;
    for (const Eigen::Vector2d& ray : rays) {
      const auto a = CameraModel::intersectGround(ray, used), b = CameraModel::intersectGround(ray, smoothed);
      if (a && b) from_used.push_back(*a), from_smoothed.push_back(*b);
    }
    mount_corrections_[i] = leastSquaresRigid(from_used, from_smoothed);
  }
}

MountState Slam::finalMount(int index) const {
  const size_t i = static_cast<size_t>(index + prior_frames_);
  if (index < 0 || i >= used_mounts_.size()) return calibratedState(calibrated_mount_);
  return i < final_mounts_.size() ? final_mounts_[i] : used_mounts_[i];
}

Pose2 Slam::finalOdometry(int index, const Pose2& odometry) const {
  const size_t i = static_cast<size_t>(index + prior_frames_);
  const auto remeasured = remeasured_odometry_.find(static_cast<int>(i));
  if (remeasured != remeasured_odometry_.end()) return remeasured->second;
  const auto refined = refined_early_odometry_.find(static_cast<int>(i));
  const Pose2& measured = refined == refined_early_odometry_.end() ? odometry : refined->second;
  if (index < 1 || i >= mount_corrections_.size() || static_cast<int>(i) - 1 < prior_frames_) return measured;
  return mount_corrections_[i - 1].inverse() * measured * mount_corrections_[i];
}

}  // namespace groundslam
