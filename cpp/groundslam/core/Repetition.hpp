#pragma once
// Not in the paper: whether the ground in an image repeats itself (tiles, bricks), told from the image alone. A fit
// on such a floor can land one repetition over with nothing to rival it (its own matches all agree on the wrong
// tile when the images barely overlap), so the pipeline must know before any fit has shown a rival.

#include <opencv2/core.hpp>

namespace groundslam {

struct RepetitionSettings {
  double highpass_px = 4.0;           ///< the light's slow changes (a Gaussian blur this wide) are taken away first
  double min_shift_fraction = 0.08;   ///< of the square's side: nearer shifts are the grain's own size
};

/// How strongly the ground in `image` (single channel, any depth) repeats: over the central square, high-passed and
/// windowed, the highest normalised autocorrelation at a shift of at least min_shift_fraction of its side that is a
/// second peak (a local maximum that rises again after a dip on the way from no shift), counted as the lesser of its
/// height and its rise over that dip. About 0.3-0.5 on tiles whose every tile carries one pattern and 0.2-0.4 on a
/// photo of bricks; up to 0.19 on asphalt, concrete, carpet, gravel and grass, whose autocorrelation only decays.
/// 0 for an image too small or blank.
double repetitionStrength(const cv::Mat& image, const RepetitionSettings& settings = {});

}  // namespace groundslam
