#pragma once
// Runs Slam over a dataset the fast way: three frames decoded, ORB-extracted, projected and matched to their
// predecessor on other threads (one FramePreparer each) while Slam's back end works on the current frame.
// What `groundslam run` does, for programs that embed groundslam.

#include <functional>
#include <vector>

#include "groundslam/io/Dataset.hpp"
#include "groundslam/pipeline/Config.hpp"
#include "groundslam/pipeline/FrameResult.hpp"
#include "groundslam/pipeline/Slam.hpp"

namespace groundslam {

struct RunnerCallbacks {
  /// After each frame: its result (in order). Optional.
  std::function<void(const FrameResult&)> on_frame;
  /// Asked before each frame: true stops the run there (frames prepared ahead are dropped). Optional.
  std::function<bool()> should_stop;
};

struct RunnerOutput {
  std::vector<FrameResult> results;  ///< one per processed frame, in order
  std::vector<double> load_ms;       ///< per frame: reading and decoding its image
};

/// Processes the dataset's frames in order with `slam` (built from `config`), then calls slam.finish().
/// Throws InputError naming the image when one cannot be read.
RunnerOutput runDataset(const Dataset& dataset, const Config& config, Slam& slam, const RunnerCallbacks& callbacks = {});

}  // namespace groundslam
