// Not in the paper: the heading of odometry edges refined by aligning the images themselves
// (core/ImageAlignment.hpp refineAlignment). Every textured pixel measures the turn: at 160 pixels wide the images'
// heading is right to about 0.01 degrees where the keypoints' is 0.02-0.04 (measured on the simulated floors). The
// two headings are combined by their variances, the images' learnt over the run from how far they are from the
// keypoints'. Where the robot's own artifacts are seen, contrast-normalised images of their own, 320 pixels wide,
// are used instead (outdoor.heading_image_width_px).
#include <algorithm>
#include <cmath>

#include "groundslam/pipeline/Slam.hpp"

namespace groundslam {
namespace {

/// T's heading moved by `weight` of `difference` toward the images'; its translation so that `pivot` (a ground point
/// of the later frame, where the fit is surest) stays where T put it; with `narrow`, the heading's variance that of
/// the combination.
void combineHeading(Pose2& T, Eigen::Matrix3d& covariance, double difference, double image_variance, const Eigen::Vector2d& pivot,
                    bool narrow) {
  const double fit_variance = covariance(2, 2);
  const double weight = fit_variance / (fit_variance + image_variance);
  const Pose2 turned(0.0, 0.0, T.theta + weight * difference);
  const Eigen::Vector2d t = T.translation() + (T.rotation() - turned.rotation()) * pivot;
  T = Pose2(t.x(), t.y(), turned.theta);
  if (!narrow) return;
  covariance(2, 2) = fit_variance * image_variance / (fit_variance + image_variance);
  for (int i = 0; i < 2; ++i) covariance(i, 2) = covariance(2, i) = (1.0 - weight) * covariance(i, 2);
}

}  // namespace

std::optional<Pose2> Slam::imageMotionDifference(const Pose2& T_a_b, const AlignmentImage& image_a, const MountState& mount_a,
                                                 const AlignmentImage& image_b, const MountState& mount_b,
                                                 const ImageAlignmentSettings& settings) const {
  const OdometryChecks& checks = config_.odometry_checks;
  // Started from the warp the fit makes through each frame's own mount: a start off by the tilts' shift (a pixel or
  // two) leaves the turn noisier (measured with tracked mounts on the standard gravel photo loop: the images' heading
  // 0.019 degrees RMS per frame from the calibrated camera's warp, 0.009 from this one; not ECC's stopping tolerance).
  const ImageAlignment aligned = refineAlignment(image_a, image_b, imageWarpOf(T_a_b, mount_a, mount_b), settings);
  if (!aligned.converged || aligned.correlation < checks.align_min_correlation) return std::nullopt;
  return T_a_b.inverse() * groundMotionOf(aligned.W_previous_current, mount_a, mount_b);
}

std::optional<double> Slam::imageHeadingVariance(HeadingImages& source, double difference, double fit_variance) const {
  Spread& spread = source.spread;
  ++source.count;
  spread.keep(difference * difference, fit_variance, source.count);
  // Images less precise than the keypoints are not used at all: a fine texture that the reduced images blur away.
  // (Where something stays still in the image, the plain images were 0.12-0.14 degrees RMS from the keypoints' and
  // 1-5% short of their turns; there the contrast-normalised heading images are used instead, Slam::process.)
  if (source.count < kLearntHeadings || lessPreciseThanKeypoints(source)) return std::nullopt;
  return learntVariance(source.spread);
}

double Slam::learntVariance(const Spread& spread) const {
  return std::max(std::pow(config_.odometry_checks.align_heading_sigma_deg * M_PI / 180.0, 2), spread.square_mean - spread.variance_mean);
}

bool Slam::lessPreciseThanKeypoints(const HeadingImages& source) const {
  return source.count >= kLearntHeadings && learntVariance(source.spread) > source.spread.variance_mean;
}

bool Slam::finerHeadingImagesBetter() const {
  if (!config_.odometry_checks.finer_heading_images || fine_headings_.count < kLearntHeadings ||
      plain_headings_.count < kLearntHeadings || lessPreciseThanKeypoints(fine_headings_)) {
    return false;
  }
  // Clearly better only: each variance is learnt from a few dozen noisy differences and floored at
  // align_heading_sigma_deg, where both images usually sit on floors the reduced ones show well.
  return lessPreciseThanKeypoints(plain_headings_) ||
         learntVariance(fine_headings_.spread) <= kFinerHeadingVarianceShare * learntVariance(plain_headings_.spread);
}

bool Slam::refineHeadingByImages(OdometryEdge& odometry, const Keyframe& current, const AlignmentImage& previous,
                                 const AlignmentImage& image, HeadingImages& source) {
  const OdometryChecks& checks = config_.odometry_checks;
  if (!(checks.align_heading_sigma_deg > 0.0) || previous.pixels.empty() || image.pixels.empty() || odometry.used.empty()) {
    return false;
  }
  const auto difference = imageMotionDifference(odometry.T_prev_curr, previous, previous_->mount, image, current.mount, source.settings);
  if (!difference) return false;
  const bool translation_agrees = difference->translation().norm() <= checks.align_check_m;
  if (!translation_agrees || std::abs(difference->theta) > checks.align_check_rad) {
    // A fit on a few dozen keypoints (fewer than odometry.align_check_below_inliers inliers) is contradicted where the
    // images agree on its translation but not on its heading: measured outdoors, a fit of 35 inliers 0.76 degrees
    // off, its covariance as small as a right fit's. Where they disagree on the translation as well, they are mostly
    // pulled toward rest by what stays still in them, and say nothing; nor do they on a fit of more inliers (measured
    // on the seen outdoor seeds 11, 23 and 41: of the fits they would contradict, 15 of 38 below 60 inliers were
    // more than 0.25 degrees off, 15 of 799 above).
    return translation_agrees && odometry.inliers < checks.align_check_below_inliers;
  }
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();  // of the fit's matches in this frame
  for (const Match& m : odometry.used) centroid += current.features.points[static_cast<size_t>(m.query)];
  centroid /= static_cast<double>(odometry.used.size());
  const auto image_variance = imageHeadingVariance(source, difference->theta, odometry.covariance(2, 2));
  // The differences the variance is learnt from, the last one too: a kind that comes into use later refines them.
  if (source.count <= kLearntHeadings) source.early.push_back({current.index, difference->theta, centroid});
  if (!image_variance) return false;
  combineHeading(odometry.T_prev_curr, odometry.covariance, difference->theta, *image_variance, centroid, source.narrows_variance);
  return false;
}

void Slam::refineEarlyHeadings(HeadingImages& source) {
  if (source.early.empty() || source.count < kLearntHeadings) return;
  if (lessPreciseThanKeypoints(source)) {
    source.early.clear();
    return;
  }
  const double image_variance = learntVariance(source.spread);
  int first_moved = static_cast<int>(graph_.poses().size());
  for (const HeadingImages::EarlyDifference& early : source.early) {
    const auto fit = early_fits_.find(early.frame);
    if (fit == early_fits_.end()) continue;
    // From the keypoints' fit, not from the edge as it stands: another kind of image may have refined it already.
    Pose2 T = fit->second.T_prev_curr;
    Eigen::Matrix3d covariance = fit->second.covariance;
    combineHeading(T, covariance, early.difference_rad, image_variance, early.pivot, source.narrows_variance);
    const GraphEdge& edge = graph_.edges()[fit->second.edge];
    graph_.remeasureEdge(fit->second.edge, T, informationFrom(covariance, config_.graph.min_sigma_m, config_.graph.min_sigma_rad));
    refined_early_odometry_[early.frame] = T;
    first_moved = std::min(first_moved, edge.to);
  }
  source.early.clear();
  if (first_moved >= static_cast<int>(graph_.poses().size())) return;
  // The poses from the first refined edge on follow (held to any loop edge among them); those before stay.
  const int first_free = std::max(first_moved, prior_frames_);
  graph_.optimise(first_free);
  if (loop_closer_) loop_closer_->mapMoved(graph_.poses(), first_free);
}

}  // namespace groundslam
