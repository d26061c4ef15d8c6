// `groundslam run DATASET`: runs SLAM on a sequence and writes the results into a run folder.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "Commands.hpp"
#include "Progress.hpp"
#include "RunOutputs.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/Tum.hpp"
#include "groundslam/pipeline/Slam.hpp"

namespace fs = std::filesystem;

namespace groundslam::apps {
namespace {

struct RunOptions {
  std::string dataset;
  std::string config;
  std::string out_dir = "runs/latest";
  bool no_loop_closure = false;
};

Config loadRunConfig(const Dataset& dataset, const RunOptions& o) {
  std::vector<std::string> layers;
  if (dataset.camera_yaml) layers.push_back(*dataset.camera_yaml);
  if (!o.config.empty()) layers.push_back(o.config);
  return loadConfig(layers);
}

void run(const RunOptions& o) {
  const Dataset dataset = openDataset(o.dataset);
  const Config config = loadRunConfig(dataset, o);
  fs::create_directories(o.out_dir);
  // A result folder must never mix a new configuration with an old trajectory.
  for (const char* stale : {"trajectory.tum", "groundtruth.tum", "frames.csv", "metrics.json"}) {
    fs::remove(fs::path(o.out_dir) / stale);
  }
  writeFileAtomically((fs::path(o.out_dir) / "config.yaml").string(), configToYaml(config));

  Slam slam(config);
  std::vector<FrameResult> results;
  std::vector<double> load_ms;
  Progress progress("run", static_cast<int>(dataset.frames.size()));
  for (const DatasetFrame& frame : dataset.frames) {
    const auto start = std::chrono::steady_clock::now();
    const cv::Mat image = loadGrayImage(frame.image_path, config.camera.image_width, config.camera.image_height);
    load_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    results.push_back(slam.process(image, frame.timestamp));
    progress.update(static_cast<int>(results.size()));
  }
  progress.finish();

  const fs::path out(o.out_dir);
  writeFileAtomically((out / "frames.csv").string(), formatFramesCsv(results, load_ms));
  writeTum((out / "trajectory.tum").string(), slam.trajectory());
  std::cout << "processed " << results.size() << " frames (" << countFallbacks(results) << " with fallback odometry)\n";
  if (dataset.hasGroundTruth()) {
    const Trajectory groundtruth = groundTruthOf(dataset, config);
    writeTum((out / "groundtruth.tum").string(), groundtruth);
    const TrajectoryMetrics metrics = evaluateTrajectory(groundtruth, slam.trajectory()).metrics;
    writeFileAtomically((out / "metrics.json").string(), metricsToJson(metrics));
    std::cout << metricsToText(metrics);
  }
  std::cout << "results in " << out.string() << "\n";
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Run SLAM on an HD Ground list or an image folder");
  cmd->add_option("DATASET", o->dataset, "HD Ground list (.txt/.test) or image folder")->required();
  cmd->add_option("--config", o->config, "Configuration YAML, applied over camera.yaml beside the dataset");
  cmd->add_option("--out", o->out_dir, "Run folder for the results")->capture_default_str();
  cmd->add_flag("--no-loop-closure", o->no_loop_closure, "Odometry only");
  cmd->callback([o]() { run(*o); });
}

}  // namespace groundslam::apps
