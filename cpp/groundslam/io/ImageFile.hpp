#pragma once
// Reading one image of a sequence as the 8-bit grey image the pipeline takes.

#include <optional>
#include <string>

#include <opencv2/core.hpp>

namespace groundslam {

/// Width and height from the first bytes of a PNG, JPEG, BMP or PGM/PPM file, without decoding it; empty for
/// other formats or when the header is unreadable (the decoder then has the last word).
std::optional<cv::Size> imageSizeFromHeader(const std::string& path);

/// 16-bit grey to 8-bit, scaled by the data's own range: sensors store 10, 12 or 14 significant bits in
/// 16-bit files, so the brightest pixel picks the smallest of 8, 10, 12, 14 or 16 bits that holds it and that
/// range maps to 0-255 (8-bit data in a 16-bit file is kept as it is).
cv::Mat toEightBit(const cv::Mat& sixteen_bit);

/// Loads an image as 8-bit grey (8- or 16-bit files; colour is converted). Throws InputError naming the
/// file when it does not decode or is not expected_width x expected_height; the size is checked from the
/// header before a large image is decoded.
cv::Mat loadGrayImage(const std::string& path, int expected_width, int expected_height);

/// Loads an image of any size as 8-bit grey, as loadGrayImage does (a texture, vocabulary training images).
cv::Mat loadGrayImageAnySize(const std::string& path);
/// An image decoded for feature extraction: `reduced_by` > 1 when the decoder shrank it by that factor itself.
struct DecodedImage {
  cv::Mat image;
  int reduced_by = 1;
};

/// As loadGrayImage, but a JPEG file is decoded already reduced by `jpeg_reduction` (2, 4 or 8; 1 = full size):
/// the decoder's scaled inverse DCT averages pixel blocks at a fraction of a full decode's cost. Other formats
/// decode at full size (their decoders cannot skip work).
DecodedImage loadGrayImageForExtraction(const std::string& path, int expected_width, int expected_height, int jpeg_reduction);

}  // namespace groundslam
