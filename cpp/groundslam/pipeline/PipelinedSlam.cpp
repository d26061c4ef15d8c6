#include "groundslam/pipeline/PipelinedSlam.hpp"

#include <exception>
#include <stdexcept>
#include <string>

namespace groundslam {

PipelinedSlam::PipelinedSlam(Slam& slam) : slam_(slam), preparer_(slam.config()) {}

PipelinedSlam::~PipelinedSlam() {
  if (ahead_.valid()) ahead_.wait();  // the preparing thread uses this object's preparer
}

std::optional<FrameResult> PipelinedSlam::push(const cv::Mat& image, double timestamp) {
  const CameraConfig& camera = slam_.config().camera;
  if (image.type() != CV_8UC1 || image.cols != camera.image_width || image.rows != camera.image_height) {
    throw std::invalid_argument("image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                (image.type() == CV_8UC1 ? "" : " (not 8-bit grey)") + ", the camera configuration says " +
                                std::to_string(camera.image_width) + "x" + std::to_string(camera.image_height) + " 8-bit grey");
  }
  cv::Mat own = image.clone();  // before the previous frame is taken: nothing is lost if this throws
  std::optional<PreparedFrame> previous;
  std::exception_ptr failure;
  if (ahead_.valid()) {
    try {
      previous = ahead_.get();
      if (ahead_unchained_) previous->matches_to_previous.reset();  // its predecessor never reached the back end
    } catch (...) {
      failure = std::current_exception();
    }
  }
  // The new frame is matched to its predecessor on the preparing thread, as soon as it has descriptors.
  const cv::Mat previous_descriptors = previous ? previous->features.descriptors : cv::Mat();
  ahead_ = std::async(std::launch::async, [this, own = std::move(own), timestamp, previous_descriptors] {
    PreparedFrame frame = preparer_.prepare(own, timestamp);
    if (!previous_descriptors.empty()) preparer_.matchToPrevious(frame, previous_descriptors);
    return frame;
  });
  ahead_unchained_ = !previous;
  if (failure) std::rethrow_exception(failure);
  if (!previous) return std::nullopt;
  try {
    return slam_.process(std::move(*previous));
  } catch (...) {
    ahead_unchained_ = true;
    throw;
  }
}

std::optional<FrameResult> PipelinedSlam::finish() {
  std::optional<FrameResult> last;
  try {
    if (ahead_.valid()) {
      PreparedFrame frame = ahead_.get();
      if (ahead_unchained_) frame.matches_to_previous.reset();
      last = slam_.process(std::move(frame));
    }
  } catch (...) {
    slam_.finish();  // the frames before still get their final optimisation
    throw;
  }
  slam_.finish();
  return last;
}

}  // namespace groundslam
