#pragma once
// Not in the paper: where a floor gives too few keypoints to fit a motion (smooth concrete, a floor of bricks
// whose only corners are the mortar joints, a floor seen through a shadow), the motion between two consecutive
// images is found by aligning the images themselves: a rigid warp maximising OpenCV's enhanced correlation
// coefficient (ECC; Evangelidis and Psarakis, PAMI 2008), started from where the robot's own steps put it.
// What stays still in the image (the robot's shadow edge, lens dirt, a bumper) is left out of the alignment.

#include <limits>
#include <vector>

#include <opencv2/core.hpp>

namespace groundslam {

struct ImageAlignmentSettings {
  int width_px = 160;               ///< images are reduced by a whole factor to this width or less before aligning
  double highpass_fraction = 0.08;  ///< background light removed: a Gaussian blur this share of the reduced width
  /// Each pixel then divided by the contrast around it (the root mean square over the same blur): the ground under
  /// a shadow counts as much as the ground in the light, and what is left of a glare's slope adds nothing.
  bool normalise_contrast = false;
  /// With normalise_contrast: pixels where the background light changes by more than this share of its level over
  /// one blur width (a shadow's edge, a glare's rim: lines the high-pass leaves that move with the light, not with
  /// the ground) are set to 0. 0: none are.
  double light_edge_slope = 0.0;
  int max_iterations = 50;          ///< ECC iterations per start
  /// A neighbourhood (7 x 7 reduced pixels) that correlates at least this well with itself at the same place
  /// in the other image stayed still while the robot moved: it is not ground and is left out.
  double still_correlation = 0.8;
  /// Starts this far (reduced pixels) from the best solution must come back to it: a solution that depends on
  /// where the alignment started is not a measurement.
  double probe_px = 3.0;
  /// refineAlignment leaves out a margin of this share of the width along every border: the background light's
  /// blur reflects the image at its borders, a pattern fixed in the image that pulls the warp toward rest
  /// (measured: 1.4% of a 14 degree turn lost without it, none with a tenth of the width).
  double refine_border_fraction = 0.1;
};

/// An image as the alignment uses it: reduced, its background light removed, its contrast normalised if asked (CV_32F).
struct AlignmentImage {
  cv::Mat pixels;
  double scale = 1.0;  ///< original image pixels per pixel of `pixels` (the decoder's and our reduction)
  /// 255 where `pixels` may show the ground, 0 on the light's edges (settings.light_edge_slope); empty: everywhere.
  cv::Mat ground;
};

/// `gray` (8-bit) was already reduced `reduced_by` times from the original image (a decoder's reduction).
AlignmentImage alignmentImage(const cv::Mat& gray, const ImageAlignmentSettings& settings, int reduced_by = 1);

/// The result of aligning two images; "did not converge" is a field, not an exception.
struct ImageAlignment {
  bool converged = false;
  cv::Matx23d W_previous_current = cv::Matx23d::eye();  ///< a pixel of the current image to the previous image's (original pixels)
  double correlation = 0.0;  ///< ECC's correlation coefficient at the solution (1: identical after the warp)
  double spread_px = 0.0;    ///< farthest any probe start ended from the solution (original pixels)
  /// The same correlation with no motion at all: near `correlation`, the images do not tell the motion from rest
  /// (what they show that is not left out as still, a lamp's glare, a shadow, moves with the camera).
  double rest_correlation = 0.0;
  /// The best correlation of the starts that ended elsewhere (farther than settings.probe_px from the solution):
  /// near `correlation`, another motion explains the images as well (a floor that repeats). -1: none did.
  double rival_correlation = -1.0;
};

/// What an alignment must show to be believed as a measurement of motion: converged, a correlation of at least
/// min_correlation, explaining the images rest_ratio times better than rest and than any rival
/// ((1 - rival) >= rest_ratio * (1 - correlation)), and probes that all come back within max_spread_m (spread_px
/// times metres_per_px). The default bar is cleared by every converged alignment.
struct AlignmentBar {
  double min_correlation = -1.0;
  double rest_ratio = 0.0;
  double max_spread_m = std::numeric_limits<double>::infinity();
  double metres_per_px = 0.0;  ///< at the image centre
};

/// Whether `aligned` clears `bar`.
bool clearsBar(const ImageAlignment& aligned, const AlignmentBar& bar);

/// 255 where the images may show moving ground, 0 where a textured neighbourhood looks the same at the same place
/// in both images (settings.still_correlation) and more alike there than where the expected warp (current pixel to
/// previous, pixels of these images) puts it: it moved with the camera.
cv::Mat movingPixels(const cv::Mat& previous, const cv::Mat& current, const cv::Matx23d& W_expected, double still_correlation);
/// The same test with the previous image already moved as the expected motion moves it (`moved_previous`: any warp,
/// a homography too); all three images CV_32F of one size.
cv::Mat movingPixels(const cv::Mat& previous, const cv::Mat& moved_previous, const cv::Mat& current, double still_correlation);

/// The rigid warp of `current` onto `previous` (both alignmentImage()s of one size) from each start (original
/// pixels, current to previous); the one of highest correlation, probed from settings.probe_px around it. The
/// first start is the expected motion that still parts are told by (movingPixels). Starts that end elsewhere are
/// rivals (rival_correlation).
/// The probes (four more alignments) are run only for a solution that clears `bar` by its correlations, and stop at the
/// first that ends farther than the bar allows: a solution that cannot clear it has spread_px infinite (not probed)
/// or that probe's distance, so clearsBar(result, bar) is what it would be with every probe run.
ImageAlignment alignImages(const AlignmentImage& previous, const AlignmentImage& current, const std::vector<cv::Matx23d>& starts,
                           const ImageAlignmentSettings& settings, const AlignmentBar& bar = {});

/// One alignment of `current` onto `previous` from `start` (original pixels, current to previous), what stays still
/// and the light's edges left out of both images (in the previous one, also where the start puts the current one's),
/// without probes (spread_px 0) or the correlation at rest (0): a motion already known to a pixel or two, made
/// precise by every textured pixel rather than the keypoints alone.
ImageAlignment refineAlignment(const AlignmentImage& previous, const AlignmentImage& current, const cv::Matx23d& start,
                               const ImageAlignmentSettings& settings);

/// Turns of the image about `centre_px` (original pixels: where the robot's origin is seen, about which a turn on
/// the spot turns the image) that make the two images most alike, tried every `step_deg` on images reduced four
/// times more: the warps (current to previous, original pixels) of the turns whose correlation is a local best and
/// within `margin` of the best one, best first. More than one: the floor looks alike turned several ways.
std::vector<cv::Matx23d> turnCandidates(const AlignmentImage& previous, const AlignmentImage& current, const cv::Point2d& centre_px,
                                        double step_deg, double margin);

/// A warp between original pixels as one between pixels of images reduced `scale` times, and back.
cv::Matx23d toReducedPixels(const cv::Matx23d& W, double scale);
cv::Matx23d toOriginalPixels(const cv::Matx23d& W_reduced, double scale);

}  // namespace groundslam
