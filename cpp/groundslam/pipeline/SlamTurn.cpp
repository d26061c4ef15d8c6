// Not in the paper: the turn of a frame whose motion failed, where it can still be measured (README *Turns from the
// spectra*): a lost segment that is never found keeps the turn assumed at its loss for good, and the previous
// motion's is a quarter turn wrong after a turn on the spot. From the same reduced images: whether the floor repeats.
#include <algorithm>
#include <cmath>

#include "groundslam/core/Repetition.hpp"
#include "groundslam/core/SpectralTurn.hpp"
#include "groundslam/pipeline/Slam.hpp"

namespace groundslam {

double Slam::imageTurnSign(const CameraModel& camera, const CameraIntrinsics& k) {
  // Seen from above the ground turns against the robot; in the image it may be mirrored too (the sign of the
  // ground-to-pixel map's determinant, measured about the ground under the image centre).
  const auto centre = camera.pixelToGround(Eigen::Vector2d(0.5 * k.width, 0.5 * k.height));
  if (!centre) return 1.0;
  const auto p0 = camera.groundToPixel(*centre), px = camera.groundToPixel(*centre + Eigen::Vector2d(1e-3, 0.0)),
             py = camera.groundToPixel(*centre + Eigen::Vector2d(0.0, 1e-3));
  if (!p0 || !px || !py) return 1.0;
  Eigen::Matrix2d J;
  J << *px - *p0, *py - *p0;
  return J.determinant() < 0.0 ? -1.0 : 1.0;
}

bool Slam::motionBySpectraAssumed(OdometryEdge& failed, const Keyframe& current, const PreparedFrame& prepared) const {
  // The registration a bridge makes (motionBySpectra): the turn, then a clear phase correlation peak at a shift of the
  // ground once it is undone. Where the floor repeats, that shift may be a repetition off: the turn alone is taken.
  if (!config_.fallback.motion_by_spectra || repetitionShown(current.index) || floor_looks_repeated_) return false;
  const auto registered = motionBySpectra(previous_turn_image_, prepared.turn, prepared.turn_scale);
  if (!registered) return false;
  failed.T_prev_curr = registered->T_tracked_current;
  failed.turn_measured = true;
  return true;
}

void Slam::turnBySpectra(OdometryEdge& failed, const cv::Mat& turn_image) const {
  const FallbackSettings& f = config_.fallback;
  if (f.turn_image_width_px <= 0 || turn_image.empty() || previous_turn_image_.size() != turn_image.size() ||
      turn_background_.size() != turn_image.size()) {
    return;
  }
  // A blank or covered image shows no turn. (Less the mean of the recent images, it would show that mean's, shared
  // with the other image's difference: no turn.) Both must show about as much contrast as each other.
  if (!comparableContrast(previous_turn_image_, turn_image)) return;
  // What stays in the image (the robot's bumper, lens dirt, vignetting) would say the robot did not turn: the mean of
  // the recent images, where the moving ground blurs away, takes it out of both.
  const cv::Mat previous = previous_turn_image_ - turn_background_, current = turn_image - turn_background_;
  const SpectralTurn found = spectralTurn(previous, current);
  if (found.peak_ratio < f.turn_min_peak_ratio) return;
  // Half a turn apart, the two turns have one spectrum. The right one, undone, leaves the images matching by a
  // translation (measured on the seen outdoor quarter turns: 4-10 times the other's phase correlation peak); where
  // that does not tell, the one clearly nearer the previous motion's turn.
  const double image_turn = found.turn_rad, image_opposite = found.turn_rad + M_PI;
  const double peak = phasePeakAfterTurn(previous, current, image_turn), opposite_peak = phasePeakAfterTurn(previous, current, image_opposite);
  const double turn = wrapAngle(image_turn_sign_ * image_turn), opposite = wrapAngle(image_turn_sign_ * image_opposite);
  double chosen = 0.0;
  if (peak >= f.turn_half_turn_ratio * opposite_peak) {
    chosen = turn;
  } else if (opposite_peak >= f.turn_half_turn_ratio * peak) {
    chosen = opposite;
  } else {
    const double previous_turn = failed.T_prev_curr.theta;
    const double off = std::abs(wrapAngle(turn - previous_turn)), opposite_off = std::abs(wrapAngle(opposite - previous_turn));
    if (std::abs(off - opposite_off) < f.turn_min_margin_deg * M_PI / 180.0) return;
    chosen = off < opposite_off ? turn : opposite;
  }
  failed.T_prev_curr = Pose2(failed.T_prev_curr.x, failed.T_prev_curr.y, chosen);
  failed.turn_measured = true;
}

bool Slam::comparableContrast(const cv::Mat& a, const cv::Mat& b) {
  cv::Scalar mean, deviation_a, deviation_b;
  cv::meanStdDev(a, mean, deviation_a);
  cv::meanStdDev(b, mean, deviation_b);
  return std::min(deviation_a[0], deviation_b[0]) >= 0.5 * std::max(deviation_a[0], deviation_b[0]);
}

void Slam::keepTurnImage(cv::Mat turn_image) {
  if (turn_image.empty()) return;
  if (turn_background_.size() != turn_image.size()) {
    turn_background_ = turn_image.clone();
    turn_images_seen_ = 1;
  } else {
    // The running mean of the first images, then an exponential one over about turn_background_frames.
    turn_images_seen_ = std::min(turn_images_seen_ + 1, std::max(1, config_.fallback.turn_background_frames));
    cv::addWeighted(turn_background_, 1.0 - 1.0 / turn_images_seen_, turn_image, 1.0 / turn_images_seen_, 0.0, turn_background_);
  }
  previous_turn_image_ = std::move(turn_image);
}

std::optional<double> Slam::measuredTurn(const RigidEstimate& refused) const {
  // Refused for its rivals or its speed, a fit of enough inliers still measures the turn: a repeated floor's rivals
  // are the same turn a tile over, and frames dropped change where the robot is, not how it turned (measured on
  // the seen outdoor seeds 11, 23 and 41 and photos 53 and 61: of 53 such fits with 25 inliers or more, 52 turned
  // within 1 degree of the truth, the previous motion 15; none was further off than the previous motion).
  const int min_inliers = config_.fallback.turn_min_inliers;
  if (min_inliers <= 0 || refused.inliers < min_inliers) return std::nullopt;
  if (refused.status != FitStatus::ambiguous && refused.status != FitStatus::implausible_motion) return std::nullopt;
  const double theta = refused.T_target_source.theta;
  for (const Pose2& rival : refused.rivals) {
    if (std::abs(wrapAngle(rival.theta - theta)) > config_.fallback.sigma_rad) return std::nullopt;  // which turn?
  }
  return theta;
}

void Slam::noteRepetition(int session_frame, const cv::Mat& turn_image) {
  const OdometryChecks& checks = config_.odometry_checks;
  if (floor_looks_repeated_ || checks.floor_repeat_check_frames <= 0 || turn_image.empty()) return;
  if (session_frame % checks.floor_repeat_check_frames != 0) return;
  const bool repeats = repetitionStrength(turn_image) >= checks.floor_repeat_min_strength;
  repeated_checks_in_a_row_ = repeats ? repeated_checks_in_a_row_ + 1 : 0;
  floor_looks_repeated_ = repeated_checks_in_a_row_ >= 2;
}

}  // namespace groundslam
