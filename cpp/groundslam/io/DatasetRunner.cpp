#include "groundslam/io/DatasetRunner.hpp"

#include <chrono>
#include <deque>
#include <future>
#include <memory>

#include <opencv2/imgproc.hpp>

#include "groundslam/io/ImageFile.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/Media.hpp"

namespace groundslam {

namespace {

struct Loaded {
  double load_ms;
  PreparedFrame frame;
};

/// A video file or camera device, read in order: while the back end works on one frame, the next is read,
/// prepared and matched to its predecessor on another thread (one at a time: a video reads in order).
RunnerOutput runVideo(const Dataset& dataset, const Config& config, Slam& slam, const RunnerCallbacks& callbacks) {
  std::unique_ptr<VideoStream> capture;
  if (dataset.video_file) {
    capture = media().openVideo(*dataset.video_file);
    if (!capture) throw InputError(*dataset.video_file + ": cannot open the video (unsupported codec or not a video)");
  } else {
    capture = media().openCamera(*dataset.camera_device);
    if (!capture) throw InputError(dataset.source + ": cannot open the camera device");
  }
  const FramePreparer preparer(config);
  const auto clock_start = std::chrono::steady_clock::now();
  long long read = 0;  // frames read from the video so far
  double last_timestamp = -1.0;
  // The next kept frame, prepared and matched to `previous` (empty at the end of the video).
  const auto next = [&](cv::Mat previous) -> std::optional<Loaded> {
    cv::Mat frame;
    for (;;) {
      const auto start = std::chrono::steady_clock::now();
      if (dataset.video_stop >= 0 && read >= dataset.video_stop) return std::nullopt;
      if (!capture->read(frame)) return std::nullopt;
      const auto arrived = std::chrono::steady_clock::now();  // a camera's frame: when read() returned it
      const long long index = read++;
      if (index < dataset.video_start || (index - dataset.video_start) % dataset.video_every != 0) continue;
      double timestamp = dataset.video_file ? capture->positionMs() / 1000.0
                                            : std::chrono::duration<double>(arrived - clock_start).count();
      // A container without usable times (or going back): the frame rate's clock, else the frame index.
      if (!(timestamp > last_timestamp)) {
        const double fps = capture->fps();
        timestamp = fps > 0.0 ? static_cast<double>(index) / fps : static_cast<double>(index);
        if (!(timestamp > last_timestamp)) timestamp = last_timestamp + 1e-3;
      }
      last_timestamp = timestamp;
      cv::Mat gray;
      if (frame.channels() == 3) cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
      else if (frame.channels() == 4) cv::cvtColor(frame, gray, cv::COLOR_BGRA2GRAY);
      else gray = frame;
      if (gray.depth() == CV_16U) gray = toEightBit(gray);
      if (gray.cols != config.camera.image_width || gray.rows != config.camera.image_height) {
        throw InputError(dataset.source + ": frame " + std::to_string(index) + " is " + std::to_string(gray.cols) + "x" +
                         std::to_string(gray.rows) + ", the camera configuration says " + std::to_string(config.camera.image_width) +
                         "x" + std::to_string(config.camera.image_height));
      }
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      Loaded loaded{ms, preparer.prepare(gray, timestamp)};
      if (!previous.empty()) preparer.matchToPrevious(loaded.frame, previous);
      return loaded;
    }
  };
  RunnerOutput output;
  std::future<std::optional<Loaded>> ahead = std::async(std::launch::async, next, cv::Mat());
  while (!(callbacks.should_stop && callbacks.should_stop())) {
    std::optional<Loaded> current = ahead.get();
    if (!current) break;
    ahead = std::async(std::launch::async, next, current->frame.features.descriptors);
    output.load_ms.push_back(current->load_ms);
    output.results.push_back(slam.process(std::move(current->frame)));
    if (callbacks.on_frame) callbacks.on_frame(output.results.back());
  }
  if (ahead.valid()) ahead.wait();
  slam.finish();
  return output;
}

}  // namespace

RunnerOutput runDataset(const Dataset& dataset, const Config& config, Slam& slam, const RunnerCallbacks& callbacks) {
  if (dataset.isVideo()) return runVideo(dataset, config, slam, callbacks);
  constexpr size_t kPrefetch = 3;  // frames in preparation, one preparer each (3: the cores never wait on a stage)
  std::vector<FramePreparer> preparers;  // built one by one: copies would share one OpenCV ORB object
  for (size_t j = 0; j < kPrefetch; ++j) preparers.emplace_back(config);
  // Frame i is matched to frame i-1 on its preparing thread as soon as i-1's descriptors exist (the back end
  // then only fits): each task publishes its descriptors and waits for its predecessor's, which was launched
  // first and waits for nobody later, so the chain cannot deadlock; a failed frame passes its error on.
  auto prepare = [&](size_t i, std::shared_ptr<std::promise<cv::Mat>> descriptors, std::shared_future<cv::Mat> previous) {
    try {
      const auto start = std::chrono::steady_clock::now();
      const DatasetFrame& frame = dataset.frames[i];
      const FramePreparer& preparer = preparers[i % kPrefetch];
      const DecodedImage decoded = loadGrayImageForExtraction(frame.image_path, config.camera.image_width,
                                                              config.camera.image_height, preparer.decoderReduction());
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      Loaded loaded{ms, preparer.prepare(decoded.image, frame.timestamp, decoded.reduced_by)};
      descriptors->set_value(loaded.frame.features.descriptors);
      if (previous.valid()) preparer.matchToPrevious(loaded.frame, previous.get());
      return loaded;
    } catch (...) {
      try {
        descriptors->set_exception(std::current_exception());
      } catch (const std::future_error&) {  // already set: the failure came after publishing
      }
      throw;
    }
  };
  std::shared_future<cv::Mat> last_descriptors;  // of the frame launched last
  const auto launch = [&](size_t j) {
    auto descriptors = std::make_shared<std::promise<cv::Mat>>();
    std::shared_future<cv::Mat> previous = last_descriptors;
    last_descriptors = descriptors->get_future().share();
    return std::async(std::launch::async, prepare, j, descriptors, previous);
  };
  const size_t n = dataset.frames.size();
  std::deque<std::future<Loaded>> ahead;  // frames i, i+1, ... in order; frame j uses preparer j % kPrefetch
  for (size_t j = 0; j < std::min(n, kPrefetch); ++j) ahead.push_back(launch(j));
  RunnerOutput output;
  for (size_t i = 0; i < n && !(callbacks.should_stop && callbacks.should_stop()); ++i) {
    Loaded current = ahead.front().get();
    ahead.pop_front();
    if (i + kPrefetch < n) ahead.push_back(launch(i + kPrefetch));
    output.load_ms.push_back(current.load_ms);
    output.results.push_back(slam.process(std::move(current.frame)));
    if (callbacks.on_frame) callbacks.on_frame(output.results.back());
  }
  for (auto& pending : ahead) pending.wait();  // frames prepared ahead of a stop are dropped
  slam.finish();
  return output;
}

}  // namespace groundslam
