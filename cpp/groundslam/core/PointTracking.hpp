#pragma once
// Not in the paper: ORB keypoints scatter by most of a pixel about the ground point they stand for (measured: 0.86
// pixels on every pyramid level of the simulated floors), so a pair of matched keypoints says where one ground point
// is in both images only to that. The camera's tilt shows in the images as a perspective distortion of about a pixel
// at the corners per degree at 320 x 240, which such pairs barely resolve (one frame's tilt change 0.25-0.7 degrees
// off). Tracking each keypoint of the current image into the previous one by the images themselves (Lucas-Kanade;
// OpenCV's implementation after Bouguet 2000, on one level) finds the same ground point to a few hundredths of a
// pixel, once the previous image is warped so that only the tilt's small distortion is left to find (a turn between
// frames biases a tracker that models a shift alone).

#include <optional>
#include <vector>

#include <opencv2/core.hpp>

namespace groundslam {

struct PointTrackingSettings {
  int width_px = 320;               ///< images are reduced by a whole factor to this width or less before tracking
  double highpass_fraction = 0.08;  ///< background light removed: a Gaussian blur this share of the reduced width
  int window_px = 15;               ///< the tracker's window (reduced pixels)
  /// Each pixel's contrast normalised over the tracker's window (see trackingImage); false: the background light
  /// removed only.
  bool normalise_contrast = true;
  /// A tracked point may move this far (reduced pixels) from where the expected warp put it: the tilt's distortion
  /// is a pixel or two, a larger move is a tracker that slid off.
  double max_shift_px = 2.0;
  /// The tracked pairs must agree with one plane-induced warp (a homography, RANSAC) to within this (reduced pixels):
  /// what is not the ground plane (the robot's shadow edge, glare, dirt) does not.
  double max_error_px = 0.3;
  /// Tracked back from the previous image, a point must land this close to where it started (reduced pixels): a
  /// window that straddles something still in the image (a shadow's edge, a bumper) tracks differently each way.
  double max_round_trip_px = 0.15;
  /// A point whose window matches worse than this many times the median window does is left out (glare, an edge).
  double max_mismatch_ratio = 2.0;
  int min_points = 20;  ///< fewer points tracked and agreeing: none are returned
  /// A point whose window overlaps what stays still in the image (a neighbourhood that correlates at least this well
  /// with itself at the same place in the other image, as in ImageAlignment's movingPixels: the robot's shadow edge,
  /// lens dirt, a bumper), in the current image or where the warp brings the previous image's, is left out; 0: none.
  double still_correlation = 0.8;
};

/// An image as the tracker uses it: reduced, its background light removed, its contrast normalised over the tracker's
/// window, 8-bit around grey 128.
struct TrackingImage {
  cv::Mat pixels;
  double scale = 1.0;  ///< original image pixels per pixel of `pixels` (the decoder's and our reduction)
};

/// `gray` (8-bit) was already reduced `reduced_by` times from the original image (a decoder's reduction).
TrackingImage trackingImage(const cv::Mat& gray, const PointTrackingSettings& settings, int reduced_by = 1);

/// Where each of `current_px` (original pixels of the current image) is in the previous image (original pixels),
/// started from `H_previous_current` (a warp of current pixels to previous ones, known to a pixel or so); empty for
/// a point that could not be tracked, slid off or disagrees with the others' plane. All empty when fewer than
/// settings.min_points remain.
std::vector<std::optional<cv::Point2d>> trackPoints(const TrackingImage& previous, const TrackingImage& current,
                                                    const std::vector<cv::Point2d>& current_px, const cv::Matx33d& H_previous_current,
                                                    const PointTrackingSettings& settings);

}  // namespace groundslam
