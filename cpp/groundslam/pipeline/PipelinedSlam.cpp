#include "groundslam/pipeline/PipelinedSlam.hpp"

#include <stdexcept>
#include <string>

namespace groundslam {

PipelinedSlam::PipelinedSlam(Slam& slam, const Config& config) : slam_(slam), config_(config), preparer_(config) {}

PipelinedSlam::~PipelinedSlam() {
  if (ahead_.valid()) ahead_.wait();  // the preparing thread uses this object's preparer
}

std::optional<FrameResult> PipelinedSlam::push(const cv::Mat& image, double timestamp) {
  if (image.type() != CV_8UC1 || image.cols != config_.camera.image_width || image.rows != config_.camera.image_height) {
    throw std::invalid_argument("image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                (image.type() == CV_8UC1 ? "" : " (not 8-bit grey)") + ", the camera configuration says " +
                                std::to_string(config_.camera.image_width) + "x" + std::to_string(config_.camera.image_height) +
                                " 8-bit grey");
  }
  std::optional<PreparedFrame> previous;
  if (ahead_.valid()) previous = ahead_.get();
  // The new frame is matched to its predecessor on the preparing thread, as soon as it has descriptors.
  const cv::Mat previous_descriptors = previous ? previous->features.descriptors : cv::Mat();
  ahead_ = std::async(std::launch::async, [this, own = image.clone(), timestamp, previous_descriptors] {
    PreparedFrame frame = preparer_.prepare(own, timestamp);
    if (!previous_descriptors.empty()) preparer_.matchToPrevious(frame, previous_descriptors);
    return frame;
  });
  if (!previous) return std::nullopt;
  return slam_.process(std::move(*previous));
}

std::optional<FrameResult> PipelinedSlam::finish() {
  std::optional<FrameResult> last;
  if (ahead_.valid()) last = slam_.process(ahead_.get());
  slam_.finish();
  return last;
}

}  // namespace groundslam
