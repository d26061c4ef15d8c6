#include "groundslam/io/DatasetRunner.hpp"

#include <chrono>
#include <deque>
#include <future>
#include <memory>

#include "groundslam/io/ImageFile.hpp"

namespace groundslam {

RunnerOutput runDataset(const Dataset& dataset, const Config& config, Slam& slam, const RunnerCallbacks& callbacks) {
  struct Loaded {
    double load_ms;
    PreparedFrame frame;
  };
  constexpr size_t kPrefetch = 2;  // frames in preparation, one preparer each
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
