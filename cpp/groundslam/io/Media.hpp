#pragma once
// Image files and video through OpenCV's imgcodecs and videoio, loaded on first use from the module
// groundslam_media. Those two libraries bring some 240 shared libraries with them (GDAL, FFmpeg, GStreamer),
// which take 0.1-0.25 s to load at every start of a program; most runs read only PNG or JPEG frames, which
// io/GrayDecoders.hpp decodes with libpng and libjpeg directly, and never need them.
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace groundslam {

/// A video file or camera device being read.
class VideoStream {
 public:
  virtual ~VideoStream() = default;
  /// The next frame; false at the end.
  virtual bool read(cv::Mat& frame) = 0;
  /// The time of the frame read last in the video, milliseconds (OpenCV's CAP_PROP_POS_MSEC).
  virtual double positionMs() const = 0;
  /// Frames per second as the container says (0 when unknown).
  virtual double fps() const = 0;
};

/// What the module provides: OpenCV's readers and writers.
class Media {
 public:
  virtual ~Media() = default;
  /// cv::imread(path, flags) with OpenCV's IMREAD_* flags; empty when the file does not decode.
  virtual cv::Mat read(const std::string& path, int flags) const = 0;
  /// cv::imwrite(path, image, params); false when it cannot be written.
  virtual bool write(const std::string& path, const cv::Mat& image, const std::vector<int>& params) const = 0;
  /// Null when the file cannot be opened as a video.
  virtual std::unique_ptr<VideoStream> openVideo(const std::string& path) const = 0;
  /// Null when the camera cannot be opened.
  virtual std::unique_ptr<VideoStream> openCamera(int index) const = 0;
};

/// The module, loaded on the first call (thread-safe). Throws InputError naming every place it looked.
const Media& media();

/// Where the module is looked for, in order: $GROUNDSLAM_MEDIA_MODULE (a file); P/lib/groundslam/ for code
/// running from P/bin or from a module under P/lib (the Python module); the build tree this code was built in;
/// the configured install prefix's lib/groundslam/.
std::vector<std::string> mediaModuleCandidates();

}  // namespace groundslam

/// The module's entry point (C linkage, found with dlsym). Its name carries the version of the Media interface
/// (v1): a module built against another version of this header is not used.
#define GROUNDSLAM_MEDIA_ENTRY groundslam_media_create_v1
#define GROUNDSLAM_MEDIA_ENTRY_NAME "groundslam_media_create_v1"
extern "C" const groundslam::Media* GROUNDSLAM_MEDIA_ENTRY();
