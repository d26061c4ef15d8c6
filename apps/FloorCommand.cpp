// `groundslam floor DATASET`: the speed floor of a run, decoding each image plus ORB extraction alone,
// single-threaded. A full run can only approach it.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>

#include <opencv2/core/utility.hpp>

#include "Commands.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"

namespace groundslam::apps {
namespace {

struct FloorOptions {
  std::string dataset;
  std::string config;
};

void measureFloor(const FloorOptions& o) {
  const Dataset dataset = openDataset(o.dataset);
  const Config config = loadDatasetConfig(dataset.camera_yaml, o.config);
  cv::setNumThreads(1);
  const OrbExtractor extractor(config.features);
  const auto start = std::chrono::steady_clock::now();
  size_t keypoints = 0;
  for (const DatasetFrame& frame : dataset.frames) {
    keypoints += extractor.detect(loadGrayImage(frame.image_path, config.camera.image_width, config.camera.image_height))
                     .keypoints.size();
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("floor: %zu frames decoded and ORB-extracted in %.2f s, single-threaded: %.2f frames/s, %.1f ms/frame (%zu keypoints)\n",
              dataset.frames.size(), seconds, static_cast<double>(dataset.frames.size()) / seconds,
              1000.0 * seconds / static_cast<double>(dataset.frames.size()), keypoints);
}

}  // namespace

void addFloorCommand(CLI::App& app) {
  auto o = std::make_shared<FloorOptions>();
  CLI::App* cmd = app.add_subcommand("floor", "Measure the speed floor: image decoding plus ORB extraction, one thread");
  cmd->add_option("DATASET", o->dataset, "HD Ground list or image folder")->required();
  cmd->add_option("--config", o->config, "Configuration YAML (its features section is used)");
  cmd->callback([o]() { measureFloor(*o); });
}

}  // namespace groundslam::apps
