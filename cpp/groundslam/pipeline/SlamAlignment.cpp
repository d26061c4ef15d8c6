// Not in the paper: odometry by aligning the images themselves where a floor gives too few keypoints, and weak
// fits checked by them (core/ImageAlignment.hpp); the rest of Slam is in Slam.cpp.
#include <algorithm>
#include <cmath>
#include <vector>

#include "groundslam/pipeline/Slam.hpp"
#include "groundslam/pipeline/StageTimer.hpp"

namespace groundslam {
namespace {

/// A motion at least this many usual steps long spans frames dropped (the spectra measure a step to a few millimetres).
constexpr double kGapSteps = 1.5;

/// Pixels spread over the image (4 x 3, inside a tenth of its size from the border) that a warp is judged on.
std::vector<Eigen::Vector2d> imageGrid(const CameraIntrinsics& k) {
  std::vector<Eigen::Vector2d> pixels;
  for (int row = 0; row < 3; ++row) {
    for (int column = 0; column < 4; ++column) {
      pixels.emplace_back(k.width * (0.1 + 0.8 * column / 3.0), k.height * (0.1 + 0.8 * row / 2.0));
    }
  }
  return pixels;
}

cv::Matx23d warpFromPose(const Pose2& T) {
  const double c = std::cos(T.theta), s = std::sin(T.theta);
  return {c, -s, T.x, s, c, T.y};
}

}  // namespace

cv::Matx23d Slam::imageWarpOf(const Pose2& T_prev_curr) const {
  std::vector<Eigen::Vector2d> current_pixels, previous_pixels;
  for (const Eigen::Vector2d& pixel : imageGrid(camera_.intrinsics())) {
    const auto ground = camera_.pixelToGround(pixel);
    if (!ground) continue;
    const auto seen_before = camera_.groundToPixel(T_prev_curr * *ground);
    if (!seen_before) continue;
    current_pixels.push_back(pixel);
    previous_pixels.push_back(*seen_before);
  }
  // A downward camera sees a rigid motion of the ground as a rigid motion of the image.
  return warpFromPose(leastSquaresRigid(previous_pixels, current_pixels));
}

cv::Matx23d Slam::imageWarpOf(const Pose2& T_prev_curr, const MountState& previous_mount, const MountState& current_mount) const {
  const CameraModel previous_camera(camera_.intrinsics(), mountFor(calibrated_mount_, previous_mount));
  const Eigen::Isometry3d current_camera = mountFor(calibrated_mount_, current_mount);
  std::vector<Eigen::Vector2d> grid = imageGrid(camera_.intrinsics()), current_pixels, previous_pixels;
  const std::vector<Eigen::Vector2d> rays = camera_.normalisedRays(grid);
  for (size_t i = 0; i < grid.size(); ++i) {
    const auto ground = CameraModel::intersectGround(rays[i], current_camera);
    if (!ground) continue;
    const auto seen_before = previous_camera.groundToPixel(T_prev_curr * *ground);
    if (!seen_before) continue;
    current_pixels.push_back(grid[i]);
    previous_pixels.push_back(*seen_before);
  }
  return warpFromPose(leastSquaresRigid(previous_pixels, current_pixels));
}

Pose2 Slam::groundMotionOf(const cv::Matx23d& W_previous_current) const {
  const MountState calibrated = calibratedState(calibrated_mount_);
  return groundMotionOf(W_previous_current, calibrated, calibrated);
}

Pose2 Slam::groundMotionOf(const cv::Matx23d& W_previous_current, const MountState& previous_mount,
                           const MountState& current_mount) const {
  std::vector<Eigen::Vector2d> current_pixels, previous_pixels;
  for (const Eigen::Vector2d& pixel : imageGrid(camera_.intrinsics())) {
    const cv::Vec2d seen_before = W_previous_current * cv::Vec3d(pixel.x(), pixel.y(), 1.0);
    current_pixels.push_back(pixel);
    previous_pixels.emplace_back(seen_before[0], seen_before[1]);
  }
  const std::vector<Eigen::Vector2d> current_rays = camera_.normalisedRays(current_pixels), previous_rays = camera_.normalisedRays(previous_pixels);
  const Eigen::Isometry3d previous_camera = mountFor(calibrated_mount_, previous_mount), current_camera = mountFor(calibrated_mount_, current_mount);
  std::vector<Eigen::Vector2d> current_ground, previous_ground;
  for (size_t i = 0; i < current_rays.size(); ++i) {
    const auto current = CameraModel::intersectGround(current_rays[i], current_camera);
    const auto previous = CameraModel::intersectGround(previous_rays[i], previous_camera);
    if (!current || !previous) continue;
    current_ground.push_back(*current);
    previous_ground.push_back(*previous);
  }
  return leastSquaresRigid(previous_ground, current_ground);
}

void Slam::keepHeadingImage(const AlignmentImage& image) {
  if (image.pixels.empty()) return;
  if (heading_background_.size() != image.pixels.size()) {
    heading_background_ = image.pixels.clone();
    heading_images_seen_ = 1;
    return;
  }
  // The running mean of the first images, then an exponential one over about turn_background_frames.
  ++heading_images_seen_;
  const int frames = std::min(heading_images_seen_, std::max(1, config_.fallback.turn_background_frames));
  cv::addWeighted(heading_background_, 1.0 - 1.0 / frames, image.pixels, 1.0 / frames, 0.0, heading_background_);
}

AlignmentBar Slam::alignmentBar(double min_correlation, double rest_ratio) const {
  // Explaining the images no better than rest is not a measurement of motion: the images' decorrelation at rest
  // must be rest_ratio (odometry.align_rest_ratio) times that after the warp.
  // Nor is explaining them no better than another motion does (a start that ended one repetition over).
  return {min_correlation, rest_ratio, config_.odometry_checks.align_max_spread_m, ground_sample_m_};
}

bool Slam::believable(const ImageAlignment& aligned, double min_correlation, double rest_ratio) const {
  return clearsBar(aligned, alignmentBar(min_correlation, rest_ratio));
}

ImageAlignment Slam::alignPair(const ImagePair& images, const std::vector<cv::Matx23d>& starts) const {
  return alignImages(images.before, images.now, starts, *images.settings, alignmentBar(images.min_correlation, images.rest_ratio));
}

std::vector<cv::Matx23d> Slam::stepStarts(int steps, bool more_steps) const {
  // Where `steps` of the robot's usual steps put the ground (at rest before any motion was measured); with more steps
  // also where 2 .. repetition_max_steps times as many put it (frames dropped without a trace). On a floor that
  // repeats, a start that ends one repetition over, as well explained, refutes the alignment (believable).
  const int most_steps = more_steps && last_good_odometry_ ? steps * std::max(1, config_.odometry_checks.repetition_max_steps) : steps;
  std::vector<cv::Matx23d> starts;
  for (int total = steps; total <= most_steps; total += steps) {
    for (const Pose2& step : last_good_odometry_ ? usualSteps() : std::vector<Pose2>{Pose2()}) {
      Pose2 motion;
      for (int k = 0; k < total; ++k) motion = motion * step;
      starts.push_back(imageWarpOf(motion));
    }
  }
  return starts;
}

Slam::ImagePair Slam::reducedImages(const AlignmentImage& before, const AlignmentImage& now) const {
  return {before, now, &alignment_settings_, config_.odometry_checks.align_min_correlation, config_.odometry_checks.align_rest_ratio};
}

std::vector<Slam::ImagePair> Slam::odometryImagePairs(const PreparedFrame& prepared) const {
  // What stays still in the image (the robot's shadow edge, its glare, lens dirt, a bumper) pulls the reduced images'
  // alignment toward rest, and on a floor too faint for its keypoints to match it is most of what they show (measured
  // on the seen OpenArena nki ground loop: started from the spectra's 1 cm step, they ended 1-8 mm from rest, at rest
  // correlations of 0.78-0.91). The heading images, their contrast normalised and the light's edges left out, see the
  // ground: 9-12 mm and 1.71-1.79 degrees of the true 10 mm and 1.80, at rest correlations of 0.10-0.12. Finer and
  // noisier, they correlate less (0.71-0.77 there).
  // What is left of the robot's own artifacts still pulls them toward rest a little: turns measured 1.4-1.8% short
  // there and on the dev nki ground loop (median -0.025 of 1.8 degrees, -0.033 of 5.5). The mean of the recent images
  // (where the moving ground blurs away and what stays in the image remains), taken away from both, leaves the ground
  // alone (median 0.000 and 0.007 there); until it holds enough images, they are aligned as they are.
  // On a smooth floor with nothing still in view the reduced images are the better ones (their blur keeps its wide
  // blobs; the heading images' own find rivals within a degree): where they tell the motion from rest clearly they are
  // believed first (measured: 7.6-9.7 times better explained than rest there; 2.0-2.1 times where, pulled by the
  // robot's artifacts, they were 0.5-1.6 degrees off on the nki ground loops).
  return imagePairs(previous_alignment_, previous_heading_, prepared.alignment, prepared.heading);
}

std::vector<Slam::ImagePair> Slam::imagePairs(const AlignmentImage& reduced_before, const AlignmentImage& heading_before,
                                              const AlignmentImage& reduced_now, const AlignmentImage& heading_now) const {
  const OdometryChecks& checks = config_.odometry_checks;
  const ImagePair reduced = reducedImages(reduced_before, reduced_now);
  if (heading_before.pixels.empty() || heading_now.pixels.empty()) return {reduced};
  ImagePair clearly_reduced = reduced;
  clearly_reduced.rest_ratio *= kClearlyBetterThanRest;
  std::vector<ImagePair> pairs = {clearly_reduced};
  const ImagePair heading{heading_before, heading_now, &artifact_headings_.settings, checks.align_heading_images_min_correlation,
                          checks.align_rest_ratio};
  if (heading_images_seen_ >= kHeadingBackgroundImages && heading_background_.size() == heading_now.pixels.size() &&
      heading_background_.size() == heading_before.pixels.size()) {
    ImagePair without_background = heading;
    without_background.before.pixels = cv::Mat();  // new pixels: the pair shares the frames' own until here
    without_background.now.pixels = cv::Mat();
    cv::subtract(heading_before.pixels, heading_background_, without_background.before.pixels);
    cv::subtract(heading_now.pixels, heading_background_, without_background.now.pixels);
    pairs.push_back(std::move(without_background));
  }
  pairs.push_back(heading);
  pairs.push_back(reduced);
  return pairs;
}

std::optional<ImageAlignment> Slam::alignFromSteps(const ImagePair& images, int steps, bool more_steps) const {
  const AlignmentImage &before = images.before, &now = images.now;
  const std::vector<cv::Matx23d> starts = stepStarts(steps, more_steps);
  const ImageAlignment aligned = alignPair(images, starts);
  if (believable(aligned, images.min_correlation, images.rest_ratio)) return aligned;
  // A turn on the spot the steps did not foresee (a sharp turn): started from the turns about the robot's origin
  // that make the images most alike, every 5 degrees, a few at most within 0.1 of the best correlation. Each is
  // aligned; where two end apart about as well explained (a floor that looks alike turned several ways, bricks turned
  // by half a turn), the turn is not known (believable).
  const auto origin_px = camera_.groundToPixel(Eigen::Vector2d::Zero());
  if (!origin_px) return std::nullopt;
  const std::vector<cv::Matx23d> turns = turnCandidates(before, now, cv::Point2d(origin_px->x(), origin_px->y()), 5.0, 0.1);
  constexpr size_t kMostTurns = 4;
  if (turns.empty() || turns.size() > kMostTurns) return std::nullopt;
  const ImageAlignment turned = alignPair(images, turns);
  if (believable(turned, images.min_correlation, images.rest_ratio)) return turned;
  return std::nullopt;
}

std::optional<OdometryEdge> Slam::odometryByAlignment(const Keyframe& previous, const Keyframe& current,
                                                      const PreparedFrame& prepared) const {
  if (!config_.odometry_checks.align_images) return std::nullopt;
  for (const ImagePair& images : odometryImagePairs(prepared)) {
    if (auto aligned = alignedFromSteps(images, previous, current)) return aligned;
  }
  return std::nullopt;
}

std::optional<OdometryEdge> Slam::alignedFromSteps(const ImagePair& images, const Keyframe& previous, const Keyframe& current) const {
  if (images.empty()) return std::nullopt;
  // From one to several usual steps: frames dropped without a trace leave no gap in the timestamps.
  const auto aligned = alignFromSteps(images, 1, true);
  if (!aligned) return std::nullopt;
  const Pose2 T_prev_curr = groundMotionOf(aligned->W_previous_current);
  if (!plausibleMotion(T_prev_curr, previous.timestamp, current.timestamp) || !movedTheRobot(T_prev_curr)) return std::nullopt;
  return alignedEdge(T_prev_curr);
}

std::optional<OdometryEdge> Slam::restRefuted(const Keyframe& previous, const Keyframe& current, const OdometryEdge& odometry,
                                              const PreparedFrame& prepared) const {
  // On a floor too faint for its own keypoints to match, those of the robot's shadow edge, lens dirt and bumper are
  // the only ones that do, and every one says the robot stands still, frame after frame: nothing shows them moving
  // against the ground. The images' spectra, less the mean of the recent images (where the moving ground blurs away
  // and what stays in the image remains), see the ground itself.
  // An alignment near rest is judged the same way: it too is pulled there by what stays in the image.
  if (!config_.odometry_checks.rest_check_by_spectra || odometry.fallback || odometry.low_overlap) return std::nullopt;
  const bool at_rest = odometry.aligned ? keypointsStayPut(odometry.T_prev_curr, current)
                                        : !odometry.used.empty() && atRest(odometry.T_prev_curr, odometry.used, current);
  if (!at_rest) return std::nullopt;
  const auto spectral = motionBySpectra(previous_turn_image_, prepared.turn, prepared.turn_scale);
  if (!spectral) return std::nullopt;  // the ground did not visibly move: rest stands
  // The motion is measured by aligning the images from where the spectra put the ground: drawn back toward rest, it
  // found what stays in the image again.
  if (auto aligned = alignedFromSpectra(previous, current, spectral->T_tracked_current, prepared)) {
    aligned->matches = odometry.matches;
    return aligned;
  }
  // Failing that, the motion is not known; the spectra's is the likeliest.
  OdometryEdge failed = odometry;
  failed.fit_status = FitStatus::still;
  failed.aligned = false;
  return fallbackOdometry(failed, std::nullopt, spectral->T_tracked_current);
}

std::optional<OdometryEdge> Slam::gapBySpectra(const Keyframe& previous, const Keyframe& current, const OdometryEdge& odometry,
                                               const PreparedFrame& prepared) const {
  // Over frames dropped without a trace the images overlap by less than half: among all of the other image's features
  // the ratio test leaves too few matches, while the spectra still register the ground. On a floor too faint for its
  // features the spectra find any other motion too, where the usual steps did not start the alignment near enough:
  // the run's first steps, a turn on the spot, the steps after a turn on the spot that was lost (their direction
  // changed with it). Not on a floor that repeats: there the spectra, like the features, register one repetition over
  // as readily.
  const OdometryChecks& checks = config_.odometry_checks;
  if (!checks.gap_by_spectra || !odometry.fallback || !tooLittleEvidence(odometry.fit_status) || repetitionShown(current.index)) {
    return std::nullopt;
  }
  const auto spectral = motionBySpectra(previous_turn_image_, prepared.turn, prepared.turn_scale);
  if (!spectral) return std::nullopt;
  const Pose2& by_spectra = spectral->T_tracked_current;
  if (unlikeTheRobotsStep(by_spectra)) {
    // The features compared only near where the spectra's motion puts them: a partner's rivals elsewhere are out of reach.
    // Fitted near that motion too, where matches along one edge can slide only as far as the spectra allow: a narrow band
    // of the images overlapping (the rest under the robot's shadow, glare or bumper) is not degenerate there (measured:
    // the 24 true matches of seven frames dropped on the held-out carpet lawnmower lay in a band 13 mm wide).
    std::vector<Match> matches = withoutRobotArtifacts(
        matchNearby(current.features, previous.features, by_spectra, checks.bridge_search_radius_m, config_.matching.ratio), previous, current);
    const TransformPrior near_the_spectra{by_spectra, checks.align_sigma_m, M_PI / 180.0};
    FitSettings near_the_spectra_fitting = odometry_fitting_;
    near_the_spectra_fitting.min_spread_inliers = 1.0;
    const RigidEstimate fit = fitMatches(matches, previous, current, near_the_spectra_fitting, near_the_spectra);
    if (fit.ok() && fit.ambiguity() <= checks.max_ambiguity && withTheSpectra(by_spectra, fit.T_target_source) &&
        movedTheRobot(fit.T_target_source)) {
      return lowOverlapEdge(fit, std::move(matches), odometry.matches);
    }
  }
  auto aligned = alignedFromSpectra(previous, current, by_spectra, prepared);
  if (aligned) aligned->matches = odometry.matches;
  return aligned;
}

std::optional<OdometryEdge> Slam::alignedFromSpectra(const Keyframe& previous, const Keyframe& current, const Pose2& by_spectra,
                                                     const PreparedFrame& prepared) const {
  // Judged as any alignment, and kept only where it stays with the spectra's motion.
  if (!config_.odometry_checks.align_images) return std::nullopt;
  const auto aligned = alignedNear(by_spectra, odometryImagePairs(prepared), 1, [&](const Pose2& T_prev_curr) {
    return plausibleMotion(T_prev_curr, previous.timestamp, current.timestamp);
  });
  if (aligned) return alignedEdge(*aligned);
  return std::nullopt;
}

std::optional<Pose2> Slam::alignedNear(const Pose2& by_spectra, const std::vector<ImagePair>& pairs, int steps,
                                       const std::function<bool(const Pose2&)>& plausible, double turn_apart_rad) const {
  const std::vector<cv::Matx23d> start = {imageWarpOf(by_spectra)};
  std::optional<ImageAlignment> reduced;  // the reduced images come twice, judged more strictly first: aligned once
  for (const ImagePair& images : pairs) {
    if (images.empty()) continue;
    const bool is_reduced = images.settings == &alignment_settings_;
    if (is_reduced && !reduced) {  // judged by the reduced images' lower bar, the stricter one's clearing it too
      reduced = alignImages(images.before, images.now, start, *images.settings,
                            alignmentBar(images.min_correlation, config_.odometry_checks.align_rest_ratio));
    }
    const ImageAlignment aligned = is_reduced ? *reduced : alignPair(images, start);
    const Pose2 T_prev_curr = groundMotionOf(aligned.W_previous_current);
    if (believable(aligned, images.min_correlation, images.rest_ratio) && withTheSpectra(by_spectra, T_prev_curr, turn_apart_rad) &&
        (!plausible || plausible(T_prev_curr)) && movedTheRobot(T_prev_curr, steps)) {
      return T_prev_curr;
    }
  }
  return std::nullopt;
}

bool Slam::unlikeTheRobotsStep(const Pose2& T_prev_curr) const {
  // Frames dropped: at least one and a half usual steps on, a motion the features could not follow. Where one usual
  // step on a weak floor gave too few matches, the features found near it are as weak (measured on the seen OpenArena
  // smooth concrete: 16 such frames of its lawnmower measured, headings up to 1.84 degrees off, the run's heading
  // 0.55 -> 4.73 degrees). A sudden turn is left to the images aligned from the spectra's motion and to the bridges,
  // which confirm it by a second frame (measured on the quarter turn of
  // Relocalization.AQuarterTurnLostOnCarpetUnderTheOutdoorLookIsFoundByItsSpectra: by the features near the spectra's
  // motion 0.72 degrees off, bridged 0.07).
  if (!last_good_odometry_) return true;
  return T_prev_curr.translation().norm() > kGapSteps * usualStep().translation().norm();
}

bool Slam::withTheSpectra(const Pose2& by_spectra, const Pose2& T_prev_curr, double turn_apart_rad) const {
  // Within the doubt an aligned motion carries (align_sigma_m) and the spectra's 1 degree (or turn_apart_rad).
  const Pose2 apart = by_spectra.inverse() * T_prev_curr;
  return apart.translation().norm() <= config_.odometry_checks.align_sigma_m && std::abs(apart.theta) <= turn_apart_rad;
}

bool Slam::movedTheRobot(const Pose2& T_prev_curr, int steps) const {
  // What stays in the image aligns best near rest (the robot's shadow and glare, a smooth floor that looks the same
  // after any small shift), turned or not: an alignment that leaves the robot nearly where it was is not believed,
  // unless it turned sharply on the spot. Nearly: less than align_min_step_share of its usual step per frame, and
  // never less than the distance that tells a moved feature from a still one: a usual step learnt from a fit at rest
  // (the first frames of a faint floor, where the robot's artifacts are all that match) is no step (measured on a
  // simulated faint loop outdoors: nine alignments in a row 0.6-1.4 mm long, where the robot drove 1 cm each).
  if (sharpTurn(T_prev_curr)) return true;
  const double share = config_.odometry_checks.align_min_step_share;
  const double least = last_good_odometry_ ? std::max(share * usualStep().translation().norm() * std::max(1, steps), share > 0.0 ? movedDistanceM() : 0.0)
                                           : movedDistanceM();
  return T_prev_curr.translation().norm() >= least;
}

OdometryEdge Slam::lowOverlapEdge(const RigidEstimate& fit, std::vector<Match> used, int matches) const {
  // Its matches crowd into the small shared area, and over a gap a rocking mount's tilt changes: less certain than
  // its fit says (odometry.low_overlap_sigma_m, low_overlap_sigma_rad).
  OdometryEdge edge{fit.T_target_source, fit.covariance, matches, fit.inliers, FitStatus::ok, false, std::move(used), fit.rms_residual_m};
  edge.low_overlap = true;
  edge.covariance += sigmaCovariance(config_.odometry_checks.low_overlap_sigma_m, config_.odometry_checks.low_overlap_sigma_rad);
  return edge;
}

OdometryEdge Slam::alignedEdge(const Pose2& T_prev_curr) const {
  OdometryEdge edge;
  edge.T_prev_curr = T_prev_curr;
  edge.covariance = sigmaCovariance(config_.odometry_checks.align_sigma_m, config_.odometry_checks.align_sigma_rad);
  edge.aligned = true;
  return edge;
}

bool Slam::keypointsStayPut(const Pose2& T_prev_curr, const Keyframe& current) const {
  return std::all_of(current.features.points.begin(), current.features.points.end(),
                     [&](const Eigen::Vector2d& p) { return (T_prev_curr * p - p).norm() < movedDistanceM(); });
}

bool Slam::atRest(const Pose2& fitted, const std::vector<Match>& used, const Keyframe& current) const {
  return std::all_of(used.begin(), used.end(), [&](const Match& m) {
    const Eigen::Vector2d& p = current.features.points[static_cast<size_t>(m.query)];
    return (fitted * p - p).norm() < movedDistanceM();
  });
}

Slam::FitCheck Slam::checkedByAlignment(const Pose2& fitted, int inliers, const std::vector<Match>& used, const Keyframe& previous,
                                        const Keyframe& current, const AlignmentImage& alignment, bool repeated_floor) const {
  const OdometryChecks& checks = config_.odometry_checks;
  FitCheck check;
  if (!checks.align_images || inliers >= checks.align_check_below_inliers || previous_alignment_.pixels.empty() ||
      alignment.pixels.empty()) {
    return check;
  }
  check.outcome = FitCheck::Outcome::unconfirmed;
  // A fit that leaves every match where it was cannot be confirmed by the images: the alignment's mask leaves out
  // what stays still where the fit moves the ground, and at rest nothing does, so the robot's own shadow edge,
  // lens dirt and bumper, which stay still whether or not it moved, pull the alignment to rest as well.
  if (atRest(fitted, used, current)) return check;
  const AlignmentBar bar = alignmentBar(checks.align_min_correlation, checks.align_rest_ratio);
  const ImageAlignment aligned = alignImages(previous_alignment_, alignment, {imageWarpOf(fitted)}, alignment_settings_, bar);
  if (!clearsBar(aligned, bar)) return check;
  const Pose2 T_prev_curr = groundMotionOf(aligned.W_previous_current);
  const Pose2 difference = fitted.inverse() * T_prev_curr;
  if (difference.translation().norm() <= checks.align_check_m && std::abs(difference.theta) <= checks.align_check_rad) {
    check.outcome = FitCheck::Outcome::confirmed;
    return check;
  }
  if (repeated_floor) return check;
  // The images disagree with the fit. Where the keypoints cannot tell the two motions apart (they sit on edges that
  // place them only across the edge) the images decide; where the keypoints refute the alignment (a fine
  // texture the reduced images blur away) the fit stands, unconfirmed.
  const auto supporting = [&](const Pose2& T) {
    return std::count_if(used.begin(), used.end(), [&](const Match& m) {
      const Eigen::Vector2d& p = current.features.points[static_cast<size_t>(m.query)];
      return (T * p - previous.features.points[static_cast<size_t>(m.train)]).norm() <= checks.align_check_radius_m;
    });
  };
  if (static_cast<double>(supporting(T_prev_curr)) < checks.align_check_support * static_cast<double>(supporting(fitted))) {
    return check;
  }
  if (!plausibleMotion(T_prev_curr, previous.timestamp, current.timestamp)) return check;
  check.outcome = FitCheck::Outcome::replaced;
  check.aligned_motion = T_prev_curr;
  return check;
}

}  // namespace groundslam
