#pragma once
// The camera's imperfections: vignetting, exposure changes, defocus, sensor noise, 8-bit quantisation.

#include <cstdint>

#include <opencv2/core.hpp>

namespace groundslam::sim {

struct PhotometricSettings {
  double noise_sigma = 2.0;          ///< sensor noise, grey levels (0-255)
  double defocus_sigma_px = 0.0;     ///< Gaussian defocus blur, pixels
  double exposure_variation = 0.0;   ///< relative amplitude of exposure changes over the run (0.2 = +-20%)
  double vignetting = 0.0;           ///< relative darkening at the image corners
  double brightness = 200.0;         ///< grey level of albedo 1 at nominal exposure
};

/// Exposure gain of a frame: a slow drift plus frame-to-frame flicker, deterministic for a seed.
double exposureGain(const PhotometricSettings& settings, int frame_index, std::uint64_t seed);

/// Turns a radiance image (CV_32F) into the 8-bit image the camera records.
cv::Mat expose(const cv::Mat& radiance, const PhotometricSettings& settings, int frame_index, std::uint64_t seed);

}  // namespace groundslam::sim
