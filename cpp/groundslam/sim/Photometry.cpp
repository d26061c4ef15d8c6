#include "groundslam/sim/Photometry.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

namespace groundslam::sim {

namespace {

/// A per-frame seed derived from the sequence seed.
std::uint64_t frameSeed(std::uint64_t seed, int frame_index, std::uint64_t salt) {
  const std::uint64_t frame = static_cast<unsigned int>(frame_index);
  return seed * salt + frame + 1u;
}

}  // namespace

double exposureGain(const PhotometricSettings& settings, int frame_index, std::uint64_t seed) {
  if (settings.exposure_variation <= 0.0) return 1.0;
  cv::RNG rng(frameSeed(seed, frame_index, 7919u));
  const double drift = std::sin(2.0 * M_PI * frame_index / 157.0 + static_cast<double>(seed % 97));
  const double flicker = rng.uniform(-1.0, 1.0);
  return 1.0 + settings.exposure_variation * (0.75 * drift + 0.25 * flicker);
}

namespace {

cv::Mat vignettingMask(cv::Size size, double strength) {
  cv::Mat mask(size, CV_32F);
  const double cx = 0.5 * (size.width - 1), cy = 0.5 * (size.height - 1);
  const double r_max2 = cx * cx + cy * cy;
  for (int row = 0; row < size.height; ++row) {
    float* p = mask.ptr<float>(row);
    for (int col = 0; col < size.width; ++col) {
      const double r2 = ((col - cx) * (col - cx) + (row - cy) * (row - cy)) / r_max2;
      p[col] = static_cast<float>(1.0 - strength * r2);
    }
  }
  return mask;
}

}  // namespace

cv::Mat expose(const cv::Mat& radiance, const PhotometricSettings& settings, int frame_index, std::uint64_t seed) {
  cv::Mat image = radiance * (settings.brightness * exposureGain(settings, frame_index, seed));
  if (settings.vignetting > 0.0) image = image.mul(vignettingMask(image.size(), settings.vignetting));
  if (settings.defocus_sigma_px > 0.0) cv::GaussianBlur(image, image, cv::Size(0, 0), settings.defocus_sigma_px);
  if (settings.noise_sigma > 0.0) {
    cv::Mat noise(image.size(), CV_32F);
    cv::RNG rng(frameSeed(seed, frame_index, 104729u));
    rng.fill(noise, cv::RNG::NORMAL, 0.0, settings.noise_sigma);
    image += noise;
  }
  cv::Mat recorded;
  image.convertTo(recorded, CV_8U);  // rounds and saturates to [0, 255]
  return recorded;
}

}  // namespace groundslam::sim
