#pragma once
// An image reduced by a whole factor, as the image alignment and the point tracker use it: reduced pixel i averages
// exactly original pixels f*i .. f*i+f-1 (whole blocks only, as for feature extraction).

#include <opencv2/core.hpp>

namespace groundslam {

struct ReducedImage {
  cv::Mat pixels;  ///< CV_32F
  int factor = 1;  ///< original pixels per reduced pixel (this reduction only)
};

/// `gray` (8-bit) reduced by the smallest whole factor that makes it `width_px` wide or less.
ReducedImage reduceByWholeFactor(const cv::Mat& gray, int width_px);

/// Reduced pixel i averages original pixels s*i .. s*i+s-1: original = s * reduced + (s - 1) / 2, as a homography.
cv::Matx33d reducedToOriginal(double scale);

}  // namespace groundslam
