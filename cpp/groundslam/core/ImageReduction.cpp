#include "groundslam/core/ImageReduction.hpp"

#include <algorithm>

#include <opencv2/imgproc.hpp>

namespace groundslam {

ReducedImage reduceByWholeFactor(const cv::Mat& gray, int width_px) {
  ReducedImage reduced;
  reduced.factor = std::max(1, (gray.cols + width_px - 1) / std::max(1, width_px));
  const int f = reduced.factor;
  const cv::Size size(std::max(1, gray.cols / f), std::max(1, gray.rows / f));
  cv::resize(gray(cv::Rect(0, 0, size.width * f, size.height * f)), reduced.pixels, size, 0.0, 0.0, cv::INTER_AREA);
  reduced.pixels.convertTo(reduced.pixels, CV_32F);
  return reduced;
}

cv::Matx33d reducedToOriginal(double scale) { return {scale, 0.0, (scale - 1.0) / 2.0, 0.0, scale, (scale - 1.0) / 2.0, 0.0, 0.0, 1.0}; }

}  // namespace groundslam
