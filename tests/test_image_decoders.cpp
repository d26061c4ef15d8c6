// The direct grey PNG / JPEG decoders give exactly what OpenCV's imread gives, and decline what they do not take.
#include <fstream>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "TestFiles.hpp"
#include "groundslam/io/GrayDecoders.hpp"
#include "groundslam/io/ImageFile.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/Media.hpp"

using namespace groundslam;
using groundslam::testing::scratchDir;

namespace {

/// A smooth pattern with noise: JPEG blocks that are neither flat nor pure noise. Odd sizes exercise partial blocks.
cv::Mat pattern(int type, int channels) {
  cv::Mat image(243, 321, CV_MAKETYPE(type, channels));
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> noise(0, 40);
  const double top = type == CV_16U ? 4000.0 : 200.0;
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) {
      for (int k = 0; k < channels; ++k) {
        const double v = top * (0.5 + 0.4 * std::sin(0.05 * c + 0.9 * k) * std::cos(0.07 * r)) + noise(rng);
        if (type == CV_16U) image.ptr<std::uint16_t>(r)[c * channels + k] = cv::saturate_cast<std::uint16_t>(v);
        else image.ptr<std::uint8_t>(r)[c * channels + k] = cv::saturate_cast<std::uint8_t>(v);
      }
    }
  }
  return image;
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

}  // namespace

TEST(GrayDecoders, GreyPngOf8And16BitsIsWhatOpenCvReads) {
  const auto dir = scratchDir();
  for (const int type : {CV_8U, CV_16U}) {
    const std::string path = (dir / (type == CV_8U ? "grey8.png" : "grey16.png")).string();
    ASSERT_TRUE(cv::imwrite(path, pattern(type, 1)));
    const std::optional<cv::Mat> ours = decodeGrayPng(path);
    ASSERT_TRUE(ours.has_value()) << path;
    EXPECT_TRUE(same(*ours, cv::imread(path, cv::IMREAD_GRAYSCALE | cv::IMREAD_ANYDEPTH))) << path;
  }
}

TEST(GrayDecoders, ColourPngIsLeftToOpenCv) {
  const auto dir = scratchDir();
  const std::string path = (dir / "colour.png").string();
  ASSERT_TRUE(cv::imwrite(path, pattern(CV_8U, 3)));
  EXPECT_FALSE(decodeGrayPng(path).has_value());
  // loadGrayImage still reads it, through the media module, as OpenCV does.
  EXPECT_TRUE(same(loadGrayImage(path, 321, 243), cv::imread(path, cv::IMREAD_GRAYSCALE)));
}

TEST(GrayDecoders, JpegAtEveryReductionIsWhatOpenCvReads) {
  const auto dir = scratchDir();
  const int flags[] = {cv::IMREAD_GRAYSCALE, cv::IMREAD_REDUCED_GRAYSCALE_2, cv::IMREAD_REDUCED_GRAYSCALE_4, cv::IMREAD_REDUCED_GRAYSCALE_8};
  for (const int channels : {1, 3}) {
    const std::string path = (dir / ("image" + std::to_string(channels) + ".jpg")).string();
    ASSERT_TRUE(cv::imwrite(path, pattern(CV_8U, channels), {cv::IMWRITE_JPEG_QUALITY, 90}));
    for (int i = 0; i < 4; ++i) {
      const int reduction = 1 << i;
      const std::optional<cv::Mat> ours = decodeGrayJpeg(path, reduction);
      ASSERT_TRUE(ours.has_value()) << path << " / " << reduction;
      EXPECT_TRUE(same(*ours, cv::imread(path, flags[i]))) << path << " / " << reduction;
    }
  }
}

TEST(GrayDecoders, ExifJpegAndBrokenFilesAreDeclined) {
  const auto dir = scratchDir();
  const std::string plain = (dir / "plain.jpg").string(), exif = (dir / "exif.jpg").string();
  ASSERT_TRUE(cv::imwrite(plain, pattern(CV_8U, 1)));
  // The same file with an EXIF segment (a TIFF header with no entries) right after the start marker: OpenCV
  // would honour an orientation tag there, so the direct decoder leaves such files to it.
  std::ifstream in(plain, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string app1 = std::string("\xFF\xE1\x00\x16", 4) + std::string("Exif\0\0", 6) + std::string("II*\0\x08\0\0\0", 8) +
                           std::string("\0\0\0\0", 4);
  std::ofstream(exif, std::ios::binary) << bytes.substr(0, 2) + app1 + bytes.substr(2);
  EXPECT_TRUE(decodeGrayJpeg(plain, 1).has_value());
  EXPECT_FALSE(decodeGrayJpeg(exif, 1).has_value());
  EXPECT_TRUE(same(loadGrayImage(exif, 321, 243), cv::imread(plain, cv::IMREAD_GRAYSCALE)));  // read by OpenCV instead
  // A PNG signature followed by rubbish, a JPEG start followed by rubbish: declined, and the loader names the file.
  for (const std::string name : {"bad.png", "bad.jpg"}) {
    const std::string path = (dir / name).string();
    std::ofstream(path, std::ios::binary) << (name == "bad.png" ? std::string("\x89PNG\r\n\x1a\n", 8) : std::string("\xFF\xD8\xFF\xE0", 4))
                                          << std::string(100, 'x');
    EXPECT_FALSE(decodeGrayPng(path).has_value()) << name;
    EXPECT_FALSE(decodeGrayJpeg(path, 1).has_value()) << name;
    try {
      loadGrayImage(path, 321, 243);
      FAIL() << name << " decoded";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
}

TEST(Media, ModuleIsFoundFromTheBuildTreeAndWritesAndReads) {
  const std::vector<std::string> candidates = mediaModuleCandidates();
  // The build tree's module comes before the configured install prefix's (an older install must not win).
  ASSERT_GE(candidates.size(), 2u);
  EXPECT_EQ(candidates[candidates.size() - 2], std::string(GROUNDSLAM_BINARY_DIR) + "/lib/groundslam/groundslam_media.so");
  const auto dir = scratchDir();
  const std::string path = (dir / "t.png").string();
  ASSERT_TRUE(media().write(path, pattern(CV_8U, 1), {}));
  EXPECT_TRUE(same(media().read(path, cv::IMREAD_GRAYSCALE), pattern(CV_8U, 1)));
  // (Video through the module: EndToEnd.VideoFileIsReadInOrderWithItsClock, in a process of its own; a failed
  // open tries every OpenCV backend, and GStreamer's leaks libusb device lists, which LeakSanitizer reports.)
}
