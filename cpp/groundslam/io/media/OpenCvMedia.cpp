// The module groundslam_media (io/Media.hpp): OpenCV's imgcodecs and videoio behind groundslam's Media
// interface, loaded only by programs that need them.
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "groundslam/io/Media.hpp"

namespace {

class OpenCvVideo : public groundslam::VideoStream {
 public:
  explicit OpenCvVideo(cv::VideoCapture capture) : capture_(std::move(capture)) {}
  bool read(cv::Mat& frame) override { return capture_.read(frame) && !frame.empty(); }
  double positionMs() const override { return capture_.get(cv::CAP_PROP_POS_MSEC); }
  double fps() const override { return capture_.get(cv::CAP_PROP_FPS); }

 private:
  cv::VideoCapture capture_;
};

class OpenCvMedia : public groundslam::Media {
 public:
  cv::Mat read(const std::string& path, int flags) const override { return cv::imread(path, flags); }
  bool write(const std::string& path, const cv::Mat& image, const std::vector<int>& params) const override {
    return cv::imwrite(path, image, params);
  }
  std::unique_ptr<groundslam::VideoStream> openVideo(const std::string& path) const override {
    cv::VideoCapture capture(path);
    return capture.isOpened() ? std::make_unique<OpenCvVideo>(std::move(capture)) : nullptr;
  }
  std::unique_ptr<groundslam::VideoStream> openCamera(int index) const override {
    cv::VideoCapture capture(index);
    return capture.isOpened() ? std::make_unique<OpenCvVideo>(std::move(capture)) : nullptr;
  }
};

}  // namespace

extern "C" const groundslam::Media* GROUNDSLAM_MEDIA_ENTRY() {
  static const OpenCvMedia media;
  return &media;
}
