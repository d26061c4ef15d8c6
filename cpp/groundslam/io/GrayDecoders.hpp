#pragma once
// Grey PNG and JPEG files decoded with libpng and libjpeg directly: the formats of nearly every image sequence,
// without loading OpenCV's image codecs (io/Media.hpp). Each gives exactly what cv::imread gives for the files it
// takes and declines the others (empty result), which then go to OpenCV.
#include <optional>
#include <string>

#include <opencv2/core.hpp>

namespace groundslam {

/// A PNG whose pixels are grey, 8 or 16 bits, not interlaced and without transparency, as cv::imread(path,
/// IMREAD_GRAYSCALE | IMREAD_ANYDEPTH) reads it (CV_8U or CV_16U); empty for any other file.
std::optional<cv::Mat> decodeGrayPng(const std::string& path);

/// A JPEG (grey or colour) decoded to 8-bit grey by libjpeg, scaled by 1 / `reduction` (1, 2, 4 or 8), as
/// cv::imread with IMREAD_GRAYSCALE or IMREAD_REDUCED_GRAYSCALE_<reduction> reads it; empty for a file with EXIF
/// data (OpenCV would turn the image by its orientation tag), a CMYK file or anything libjpeg refuses.
std::optional<cv::Mat> decodeGrayJpeg(const std::string& path, int reduction);

}  // namespace groundslam
