#pragma once
// Slam fed one image at a time by a camera driver, the fast way: while Slam's back end (odometry fit, loop
// closure, optimisation) works on one frame, the next frame is ORB-extracted, projected and matched to its
// predecessor on another thread. What runDataset does for a dataset, for images that arrive one by one.

#include <future>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "groundslam/pipeline/Config.hpp"
#include "groundslam/pipeline/FramePreparer.hpp"
#include "groundslam/pipeline/FrameResult.hpp"
#include "groundslam/pipeline/Slam.hpp"

namespace groundslam {

class PipelinedSlam {
 public:
  /// Images are prepared with `slam`'s configuration. `slam` must outlive this object; nothing else may call it
  /// meanwhile.
  explicit PipelinedSlam(Slam& slam);
  /// Waits for the frame in preparation, if any (its result is dropped when finish() was not called).
  ~PipelinedSlam();
  PipelinedSlam(const PipelinedSlam&) = delete;
  PipelinedSlam& operator=(const PipelinedSlam&) = delete;

  /// Hands over the next image (8-bit grey, the camera's size; copied, so the caller may reuse its buffer).
  /// Its preparation starts on another thread, and the previous image goes through the back end here: the
  /// result returned is the previous frame's (empty for the first image). Results come one frame late, in order,
  /// identical to Slam::process on the same images.
  /// Throws std::invalid_argument (nothing pushed) for an image of the wrong size or type. An exception from
  /// the previous frame (its preparation or the back end) is thrown here after this image has been taken;
  /// the next frame is then matched to its predecessor by the back end, as Slam::process would.
  std::optional<FrameResult> push(const cv::Mat& image, double timestamp);
  /// Processes the frame still in preparation, then optimises the whole graph (Slam::finish); returns that
  /// frame's result (empty when no image was pushed since the last finish).
  std::optional<FrameResult> finish();

 private:
  Slam& slam_;
  FramePreparer preparer_;
  std::future<PreparedFrame> ahead_;  ///< the frame in preparation
  /// The frame in preparation was matched to one that did not reach the back end: its matches are dropped.
  bool ahead_unchained_ = false;
};

}  // namespace groundslam
