#include "groundslam/core/Repetition.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace groundslam {

double repetitionStrength(const cv::Mat& image, const RepetitionSettings& settings) {
  if (image.empty() || image.channels() != 1) return 0.0;
  const int side = std::min(image.cols, image.rows);
  if (side < 16) return 0.0;
  cv::Mat square, background;
  image(cv::Rect((image.cols - side) / 2, (image.rows - side) / 2, side, side)).convertTo(square, CV_32F);
  cv::GaussianBlur(square, background, cv::Size(0, 0), settings.highpass_px);
  square -= background;
  cv::Mat window;
  cv::createHanningWindow(window, square.size(), CV_32F);
  square = square.mul(window);
  // The autocorrelation from the power spectrum (Wiener-Khinchin), normalised by its value at no shift.
  cv::Mat spectrum, power, autocorrelation;
  cv::dft(square, spectrum, cv::DFT_COMPLEX_OUTPUT);
  cv::mulSpectrums(spectrum, spectrum, power, 0, true);
  cv::dft(power, autocorrelation, cv::DFT_INVERSE | cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  const float at_rest = autocorrelation.at<float>(0, 0);
  if (!(at_rest > 0.0f)) return 0.0;
  autocorrelation /= at_rest;
  const auto at = [&](double x, double y) {
    const auto wrap = [side](long i) { return static_cast<int>(((i % side) + side) % side); };
    return static_cast<double>(autocorrelation.at<float>(wrap(std::lround(y)), wrap(std::lround(x))));
  };
  constexpr double kLeastPeak = 0.1;  // below it, a local maximum is the noise of the autocorrelation
  const double min_shift = settings.min_shift_fraction * side;
  double strongest = 0.0;
  for (int y = -side / 2; y < side / 2; ++y) {
    for (int x = -side / 2; x < side / 2; ++x) {
      if (std::hypot(x, y) < min_shift) continue;
      const double value = at(x, y);
      if (value < kLeastPeak) continue;
      bool local_maximum = true;
      for (int dy = -1; dy <= 1 && local_maximum; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if ((dx != 0 || dy != 0) && at(x + dx, y + dy) > value) {
            local_maximum = false;
            break;
          }
        }
      }
      if (!local_maximum) continue;
      // A grain drawn out along one direction keeps correlating along it, but only ever less: no dip before it.
      double dip = value;
      for (int step = 4; step <= 16; ++step) dip = std::min(dip, at(x * step / 20.0, y * step / 20.0));
      strongest = std::max(strongest, std::min(value, value - dip));
    }
  }
  return strongest;
}

}  // namespace groundslam
