#include "groundslam/io/ImageFile.hpp"

#include <array>
#include <cctype>
#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>  // the IMREAD_* flags only: decoding goes through GrayDecoders or the media module

#include "groundslam/io/GrayDecoders.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/Media.hpp"

namespace groundslam {
namespace {

unsigned bigEndian(const unsigned char* p, int bytes) {
  unsigned value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | p[i];
  return value;
}

unsigned littleEndian(const unsigned char* p, int bytes) {
  unsigned value = 0;
  for (int i = bytes - 1; i >= 0; --i) value = (value << 8) | p[i];
  return value;
}

std::optional<cv::Size> sizeOf(unsigned width, unsigned height) {
  if (width == 0 || height == 0 || width > 1000000 || height > 1000000) return std::nullopt;
  return cv::Size(static_cast<int>(width), static_cast<int>(height));
}

/// JPEG: walks the markers to the first start-of-frame (SOF0-SOF15 but DHT, JPG and DAC).
std::optional<cv::Size> jpegSize(std::ifstream& in) {
  in.seekg(2);
  std::array<unsigned char, 9> segment{};
  for (int markers = 0; markers < 1000 && in.read(reinterpret_cast<char*>(segment.data()), 4); ++markers) {
    if (segment[0] != 0xFF) return std::nullopt;
    const unsigned marker = segment[1], length = bigEndian(&segment[2], 2);
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      if (!in.read(reinterpret_cast<char*>(segment.data()), 5)) return std::nullopt;
      return sizeOf(bigEndian(&segment[3], 2), bigEndian(&segment[1], 2));
    }
    if (length < 2) return std::nullopt;
    in.seekg(static_cast<std::streamoff>(length) - 2, std::ios::cur);
  }
  return std::nullopt;
}

/// PGM/PPM (P2, P3, P5, P6): width and height are the first two numbers after the magic, comments skipped.
std::optional<cv::Size> netpbmSize(std::ifstream& in) {
  in.seekg(2);
  unsigned numbers[2] = {0, 0};
  for (unsigned& number : numbers) {
    int c = in.get();
    while (c != EOF && (std::isspace(c) || c == '#')) {
      if (c == '#') while (c != EOF && c != '\n') c = in.get();
      c = in.get();
    }
    if (c == EOF || !std::isdigit(c)) return std::nullopt;
    for (; c != EOF && std::isdigit(c) && number < 10000000; c = in.get()) number = number * 10 + static_cast<unsigned>(c - '0');
  }
  return sizeOf(numbers[0], numbers[1]);
}

}  // namespace

std::optional<cv::Size> imageSizeFromHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<unsigned char, 26> head{};
  if (!in.read(reinterpret_cast<char*>(head.data()), head.size())) return std::nullopt;
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (std::equal(kPng, kPng + 8, head.begin())) return sizeOf(bigEndian(&head[16], 4), bigEndian(&head[20], 4));
  if (head[0] == 0xFF && head[1] == 0xD8) return jpegSize(in);
  if (head[0] == 'B' && head[1] == 'M') {
    // BITMAPINFOHEADER: signed width and height (negative height: rows stored top-down).
    const int width = static_cast<int>(littleEndian(&head[18], 4)), height = static_cast<int>(littleEndian(&head[22], 4));
    return sizeOf(static_cast<unsigned>(std::abs(width)), static_cast<unsigned>(std::abs(height)));
  }
  if (head[0] == 'P' && (head[1] == '2' || head[1] == '3' || head[1] == '5' || head[1] == '6')) return netpbmSize(in);
  return std::nullopt;
}

cv::Mat toEightBit(const cv::Mat& sixteen_bit) {
  double max_value = 0.0;
  cv::minMaxLoc(sixteen_bit, nullptr, &max_value);
  int bits = 8;
  while (bits < 16 && max_value > (1 << bits) - 1) bits += 2;
  cv::Mat eight_bit;
  sixteen_bit.convertTo(eight_bit, CV_8U, 255.0 / ((1 << bits) - 1));
  return eight_bit;
}

namespace {

bool isJpeg(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[3] = {0, 0, 0};
  return in.read(reinterpret_cast<char*>(head), 3) && head[0] == 0xFF && head[1] == 0xD8 && head[2] == 0xFF;
}

InputError wrongSize(const std::string& path, int width, int height, int expected_width, int expected_height) {
  return InputError(path + ": image is " + std::to_string(width) + "x" + std::to_string(height) +
                    ", the camera configuration says " + std::to_string(expected_width) + "x" + std::to_string(expected_height));
}

/// Refuses an image whose header gives another size, before it is decoded.
void checkHeaderSize(const std::string& path, int expected_width, int expected_height) {
  if (const auto size = imageSizeFromHeader(path); size && (size->width != expected_width || size->height != expected_height)) {
    throw wrongSize(path, size->width, size->height, expected_width, expected_height);
  }
}

/// The image as cv::imread(path, flags) gives it: grey PNG and JPEG decoded here, anything else by OpenCV in the
/// media module. `reduction` > 1: a JPEG reduced by that factor (flags then ask for the same).
cv::Mat readImage(const std::string& path, int flags, int reduction) {
  std::optional<cv::Mat> image = isJpeg(path) ? decodeGrayJpeg(path, reduction) : reduction == 1 ? decodeGrayPng(path) : std::nullopt;
  return image ? *image : media().read(path, flags);
}

int reducedReadFlag(int factor) {
  switch (factor) {
    case 2: return cv::IMREAD_REDUCED_GRAYSCALE_2;
    case 4: return cv::IMREAD_REDUCED_GRAYSCALE_4;
    case 8: return cv::IMREAD_REDUCED_GRAYSCALE_8;
    default: return 0;
  }
}

}  // namespace

DecodedImage loadGrayImageForExtraction(const std::string& path, int expected_width, int expected_height, int jpeg_reduction) {
  const int flag = reducedReadFlag(jpeg_reduction);
  if (flag == 0 || !isJpeg(path)) return DecodedImage{loadGrayImage(path, expected_width, expected_height), 1};
  checkHeaderSize(path, expected_width, expected_height);
  cv::Mat image = readImage(path, flag, jpeg_reduction);
  if (image.empty()) throw InputError(path + ": image does not decode");
  // The scaled decoder rounds the size up: ceil(size / factor).
  const int width = (expected_width + jpeg_reduction - 1) / jpeg_reduction;
  const int height = (expected_height + jpeg_reduction - 1) / jpeg_reduction;
  if (image.depth() != CV_8U || image.cols != width || image.rows != height) {
    return DecodedImage{loadGrayImage(path, expected_width, expected_height), 1};  // the full decoder has the last word
  }
  return DecodedImage{image, jpeg_reduction};
}

cv::Mat loadGrayImageAnySize(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) throw InputError(path + ": image not found");
  cv::Mat image = readImage(path, cv::IMREAD_GRAYSCALE | cv::IMREAD_ANYDEPTH, 1);
  if (image.empty()) throw InputError(path + ": image does not decode");
  if (image.depth() == CV_16U) image = toEightBit(image);
  if (image.depth() != CV_8U) throw InputError(path + ": pixels are not 8- or 16-bit integers (floating-point images are not read)");
  return image;
}

cv::Mat loadGrayImage(const std::string& path, int expected_width, int expected_height) {
  checkHeaderSize(path, expected_width, expected_height);  // (a missing file has no header: named just below)
  const cv::Mat image = loadGrayImageAnySize(path);
  if (image.cols != expected_width || image.rows != expected_height) throw wrongSize(path, image.cols, image.rows, expected_width, expected_height);
  return image;
}

}  // namespace groundslam
