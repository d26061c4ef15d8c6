// `groundslam floor DATASET`: the speed floor of a run, decoding each image plus ORB extraction alone,
// single-threaded: with OpenCV's default ORB (the reference any ORB-based system pays) and with groundslam's
// own extraction settings (what a run's frame preparers pay).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>

#include "Commands.hpp"
#include "Progress.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/ImageFile.hpp"

namespace groundslam::apps {
namespace {

struct FloorOptions {
  std::string dataset;
  std::string config;
};

/// Decodes and extracts every image of the dataset on this thread; prints one line and returns ms per frame.
template <class Extract>
double timeExtraction(const Dataset& dataset, const char* label, Extract&& extract) {
  const auto start = std::chrono::steady_clock::now();
  size_t keypoints = 0;
  Progress progress("floor", static_cast<int>(dataset.frames.size()));  // on a terminal only (stderr)
  int done = 0;
  for (const DatasetFrame& frame : dataset.frames) {
    keypoints += extract(frame.image_path);
    progress.update(++done);
  }
  progress.finish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double frames = static_cast<double>(dataset.frames.size());
  std::printf("%s: %zu frames in %.2f s, single-threaded: %.2f frames/s, %.1f ms/frame (%zu keypoints)\n", label,
              dataset.frames.size(), seconds, frames / seconds, 1000.0 * seconds / frames, keypoints);
  return 1000.0 * seconds / frames;
}

void measureFloor(const FloorOptions& o) {
  const Dataset dataset = openDataset(o.dataset);
  if (dataset.isVideo()) throw InputError(dataset.source + ": `floor` reads image datasets (a video or camera: groundslam run)");
  const Config config = loadDatasetConfig(dataset.camera_yaml, o.config).config;
  cv::setNumThreads(1);
  const int width = config.camera.image_width, height = config.camera.image_height;
  // The reference: a plain decode and OpenCV's ORB with its defaults (1000 features, 8 levels, FAST
  // threshold 20) on the full image, what any ORB-based system pays per frame.
  const cv::Ptr<cv::ORB> reference = cv::ORB::create();
  timeExtraction(dataset, "floor (decode + OpenCV default ORB, full resolution)", [&](const std::string& path) {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    reference->detectAndCompute(loadGrayImage(path, width, height), cv::noArray(), keypoints, descriptors);
    return keypoints.size();
  });
  // What groundslam's frame preparers do: the cheapest decode for the extraction, then the configured ORB.
  const OrbExtractor extractor(config.features);
  const int jpeg_reduction = decoderReductionFor(width, config.features.max_extraction_width);
  timeExtraction(dataset, "groundslam extraction (decode + ORB as configured)", [&](const std::string& path) {
    const DecodedImage decoded = loadGrayImageForExtraction(path, width, height, jpeg_reduction);
    return extractor.detect(decoded.image, decoded.reduced_by).keypoints.size();
  });
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
