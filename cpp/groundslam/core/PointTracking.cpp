#include "groundslam/core/PointTracking.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "groundslam/core/ImageAlignment.hpp"
#include "groundslam/core/ImageReduction.hpp"

namespace groundslam {
namespace {

/// Grey levels per standard deviation of a window's contrast in the tracking image (8-bit around 128: +-4 sigma).
constexpr double kNormalisedContrast = 30.0;

cv::Point2d apply(const cv::Matx33d& H, const cv::Point2d& p) {
  const cv::Vec3d q = H * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

/// 255 within `reach` pixels of what stays still between the two images (CV_8U, current pixels): the still parts
/// themselves and where the warp (current pixel -> previous pixel) brings the previous image's still parts. Told on
/// images halved again, at the scale the images' alignment tells them (measured on a blurred noise floor at full
/// scale: 2.6% of a clean floor's pixels looked still by chance, a 7 x 7 window holding too few independent grains).
cv::Mat nearStillParts(const cv::Mat& previous, const cv::Mat& warped, const cv::Mat& current, const cv::Matx33d& H,
                       double still_correlation, int reach) {
  const cv::Size half(std::max(1, current.cols / 2), std::max(1, current.rows / 2));
  cv::Mat previous32, warped32, current32;
  for (auto [from, to] : {std::pair{&previous, &previous32}, std::pair{&warped, &warped32}, std::pair{&current, &current32}}) {
    cv::Mat reduced;
    cv::resize(*from, reduced, half, 0.0, 0.0, cv::INTER_AREA);
    reduced.convertTo(*to, CV_32F);
  }
  cv::Mat still;
  cv::resize(movingPixels(previous32, warped32, current32, still_correlation) == 0, still, current.size(), 0.0, 0.0, cv::INTER_NEAREST);
  cv::Mat still_in_warped;
  cv::warpPerspective(still, still_in_warped, H, still.size(), cv::INTER_NEAREST | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, 0);
  cv::Mat near = still | still_in_warped;
  cv::dilate(near, near, cv::Mat::ones(2 * reach + 1, 2 * reach + 1, CV_8U));
  return near;
}

}  // namespace

TrackingImage trackingImage(const cv::Mat& gray, const PointTrackingSettings& settings, int reduced_by) {
  TrackingImage tracking;
  if (gray.empty()) return tracking;
  const ReducedImage reduced_image = reduceByWholeFactor(gray, settings.width_px);
  const cv::Mat& reduced = reduced_image.pixels;
  const cv::Size size = reduced.size();
  // The background light is smooth: blurred on an image reduced four times more, then brought back (a blur of 26
  // pixels on the 320-wide image itself cost 2.7 ms a frame).
  constexpr int kCoarse = 4;
  const cv::Size coarse_size(std::max(1, size.width / kCoarse), std::max(1, size.height / kCoarse));
  cv::Mat coarse, background;
  cv::resize(reduced, coarse, coarse_size, 0.0, 0.0, cv::INTER_AREA);
  cv::GaussianBlur(coarse, coarse, cv::Size(0, 0), std::max(1.0, settings.highpass_fraction * size.width / kCoarse), 0.0,
                   cv::BORDER_REFLECT);
  cv::resize(coarse, background, size, 0.0, 0.0, cv::INTER_LINEAR);
  // Then each pixel's contrast over the tracker's window: what the robot's glare adds and its shadow takes away
  // stays at its place in the image while the pre-warp moves the previous image under it; normalised, a window
  // compares texture, not light (measured: a rocking outdoor carpet loop with glare, its tilt 0.48 -> 0.22 degrees
  // off; see docs/accuracy.md, Session 21).
  cv::Mat light, removed, mean, square_mean, spread;
  reduced.convertTo(light, CV_32F);
  background.convertTo(removed, CV_32F);
  light -= removed;
  tracking.scale = static_cast<double>(reduced_image.factor) * std::max(1, reduced_by);
  if (!settings.normalise_contrast) {
    cv::Mat(light + 128.0).convertTo(tracking.pixels, CV_8U);
    return tracking;
  }
  const int window = std::max(5, settings.window_px | 1);
  cv::blur(light, mean, cv::Size(window, window));
  cv::blur(light.mul(light), square_mean, cv::Size(window, window));
  cv::sqrt(cv::max(square_mean - mean.mul(mean), 1.0), spread);
  const cv::Mat normalised = (light - mean) / spread * kNormalisedContrast + 128.0;
  normalised.convertTo(tracking.pixels, CV_8U);
  return tracking;
}

std::vector<std::optional<cv::Point2d>> trackPoints(const TrackingImage& previous, const TrackingImage& current,
                                                    const std::vector<cv::Point2d>& current_px, const cv::Matx33d& H_previous_current,
                                                    const PointTrackingSettings& settings) {
  std::vector<std::optional<cv::Point2d>> tracked(current_px.size());
  if (previous.pixels.empty() || previous.pixels.size() != current.pixels.size() || previous.scale != current.scale ||
      current_px.size() < static_cast<size_t>(std::max(4, settings.min_points))) {
    return tracked;
  }
  const cv::Matx33d S = reducedToOriginal(current.scale);
  const cv::Matx33d H = S.inv() * H_previous_current * S;  // reduced current pixel -> reduced previous pixel
  // The previous image as the current one would show it under the expected warp: only the residual is tracked.
  cv::Mat warped;
  cv::warpPerspective(previous.pixels, warped, H, previous.pixels.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
  std::vector<cv::Point2f> from, to;
  for (const cv::Point2d& p : current_px) {
    const cv::Point2d r = apply(S.inv(), p);
    from.emplace_back(static_cast<float>(r.x), static_cast<float>(r.y));
  }
  to = from;
  std::vector<unsigned char> status;
  std::vector<float> error;
  const int window = std::max(5, settings.window_px | 1);
  // One level: the pre-warp leaves a pixel or two to find, well inside the window.
  cv::calcOpticalFlowPyrLK(current.pixels, warped, from, to, status, error, cv::Size(window, window), 0,
                           cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01), cv::OPTFLOW_USE_INITIAL_FLOW);
  // Back again: a point must return to where it started (forward-backward error, Kalal et al. 2010).
  std::vector<cv::Point2f> back = from;
  std::vector<unsigned char> back_status;
  std::vector<float> back_error;
  cv::calcOpticalFlowPyrLK(warped, current.pixels, to, back, back_status, back_error, cv::Size(window, window), 0,
                           cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01), cv::OPTFLOW_USE_INITIAL_FLOW);
  // The window's half width and the farthest a point may move: a window near a still part may straddle it.
  const int reach = window / 2 + static_cast<int>(std::ceil(settings.max_shift_px));
  const cv::Mat near_still = settings.still_correlation > 0.0
                                 ? nearStillParts(previous.pixels, warped, current.pixels, H, settings.still_correlation, reach)
                                 : cv::Mat();
  std::vector<float> mismatches;
  for (size_t i = 0; i < from.size(); ++i) {
    if (status[i] && std::isfinite(error[i])) mismatches.push_back(error[i]);
  }
  if (mismatches.empty()) return tracked;
  std::nth_element(mismatches.begin(), mismatches.begin() + static_cast<std::ptrdiff_t>(mismatches.size() / 2), mismatches.end());
  const double max_mismatch = settings.max_mismatch_ratio * mismatches[mismatches.size() / 2];
  // Points near the border: the warped image repeats its edge there.
  const double margin = 0.5 * window;
  const cv::Rect2d inside(margin, margin, current.pixels.cols - 2.0 * margin, current.pixels.rows - 2.0 * margin);
  std::vector<size_t> kept;
  std::vector<cv::Point2f> kept_current, kept_previous;
  for (size_t i = 0; i < from.size(); ++i) {
    if (!status[i] || !back_status[i] || !std::isfinite(to[i].x) || !std::isfinite(to[i].y)) continue;
    if (std::hypot(back[i].x - from[i].x, back[i].y - from[i].y) > settings.max_round_trip_px || error[i] > max_mismatch) continue;
    if (std::hypot(to[i].x - from[i].x, to[i].y - from[i].y) > settings.max_shift_px) continue;
    if (!inside.contains(cv::Point2d(from[i])) || !inside.contains(cv::Point2d(to[i]))) continue;
    if (!near_still.empty() && near_still.at<unsigned char>(cvRound(from[i].y), cvRound(from[i].x)) != 0) continue;
    const cv::Point2d previous_reduced = apply(H, cv::Point2d(to[i]));
    kept.push_back(i);
    kept_current.push_back(from[i]);
    kept_previous.emplace_back(static_cast<float>(previous_reduced.x), static_cast<float>(previous_reduced.y));
  }
  if (kept.size() < static_cast<size_t>(std::max(4, settings.min_points))) return tracked;
  // One plane: the pairs that a single homography explains to settings.max_error_px (seeded: OpenCV's RANSAC draws
  // from its own fixed-seed generator, so a run repeats).
  std::vector<unsigned char> agrees;
  const cv::Mat fitted = cv::findHomography(kept_current, kept_previous, cv::RANSAC, settings.max_error_px, agrees, 2000, 0.999);
  if (fitted.empty() || agrees.size() != kept.size()) return tracked;
  if (std::count(agrees.begin(), agrees.end(), 1) < std::max(4, settings.min_points)) return tracked;
  for (size_t k = 0; k < kept.size(); ++k) {
    if (agrees[k]) tracked[kept[k]] = apply(S, cv::Point2d(kept_previous[k]));
  }
  return tracked;
}

}  // namespace groundslam
