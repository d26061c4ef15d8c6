// `groundslam run DATASET`: runs SLAM on a sequence and writes the results into a run folder.
#include <chrono>
#include <deque>
#include <filesystem>
#include <future>
#include <iostream>
#include <memory>

#include "Commands.hpp"
#include "Progress.hpp"
#include "RunOutputs.hpp"
#include "groundslam/eval/LoopClosureMetrics.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/RunFiles.hpp"
#include "groundslam/io/Tum.hpp"
#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/pipeline/Slam.hpp"

namespace fs = std::filesystem;

namespace groundslam::apps {
namespace {

struct RunOptions {
  std::string dataset;
  std::string config;
  std::string out_dir = "runs/latest";
  bool no_loop_closure = false;
  bool report = false;
};

Config loadRunConfig(const Dataset& dataset, const RunOptions& o) {
  Config config = loadDatasetConfig(dataset.camera_yaml, o.config);
  if (o.no_loop_closure) config.loop_closure.enabled = false;
  return config;
}

std::shared_ptr<const Vocabulary> loadVocabulary(const Config& config) {
  if (!config.loop_closure.enabled) return nullptr;
  const std::string path = config.loop_closure.vocabulary.empty() ? defaultVocabularyPath() : config.loop_closure.vocabulary;
  return std::make_shared<const Vocabulary>(readVocabulary(path));
}

/// Runs every frame through the pipeline, with a progress line on a terminal. The next frames are decoded
/// and their features extracted on other threads (a FramePreparer each) while the current one goes
/// through the back end, so both cores stay busy.
std::vector<FrameResult> processAll(const Dataset& dataset, const Config& config, Slam& slam, std::vector<double>& load_ms) {
  struct Loaded {
    double load_ms;
    PreparedFrame frame;
  };
  constexpr size_t kPrefetch = 2;  // frames in preparation, one preparer each
  std::vector<FramePreparer> preparers;  // built one by one: copies would share one OpenCV ORB object
  for (size_t j = 0; j < kPrefetch; ++j) preparers.emplace_back(config);
  auto prepare = [&](size_t i) {
    const auto start = std::chrono::steady_clock::now();
    const DatasetFrame& frame = dataset.frames[i];
    const cv::Mat image = loadGrayImage(frame.image_path, config.camera.image_width, config.camera.image_height);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return Loaded{ms, preparers[i % kPrefetch].prepare(image, frame.timestamp)};
  };
  const size_t n = dataset.frames.size();
  std::deque<std::future<Loaded>> ahead;  // frames i, i+1, ... in order; frame j uses preparer j % kPrefetch
  for (size_t j = 0; j < std::min(n, kPrefetch); ++j) ahead.push_back(std::async(std::launch::async, prepare, j));
  std::vector<FrameResult> results;
  Progress progress("run", static_cast<int>(n));
  for (size_t i = 0; i < n; ++i) {
    Loaded current = ahead.front().get();
    ahead.pop_front();
    if (i + kPrefetch < n) ahead.push_back(std::async(std::launch::async, prepare, i + kPrefetch));
    load_ms.push_back(current.load_ms);
    results.push_back(slam.process(std::move(current.frame)));
    progress.update(static_cast<int>(results.size()));
  }
  slam.finish();
  progress.finish();
  return results;
}

void run(const RunOptions& o) {
  const Dataset dataset = openDataset(o.dataset);
  const Config config = loadRunConfig(dataset, o);
  Slam slam(config, loadVocabulary(config));
  const fs::path out(o.out_dir);
  fs::create_directories(out);
  // A result folder must never mix a new configuration with an old trajectory.
  for (const char* stale : {"trajectory.tum", "groundtruth.tum", "frames.csv", "metrics.json", "loop_closures.csv",
                            "candidates.csv", "graph.g2o"}) {
    fs::remove(out / stale);
  }
  writeFileAtomically((out / "config.yaml").string(), configToYaml(config));

  std::vector<double> load_ms;
  const std::vector<FrameResult> results = processAll(dataset, config, slam, load_ms);
  const Trajectory trajectory = slam.trajectory();
  writeFileAtomically((out / "frames.csv").string(), formatFramesCsv(results, load_ms));
  writeFileAtomically((out / "loop_closures.csv").string(), formatLoopClosuresCsv(slam.loopCandidates()));
  writeFileAtomically((out / "graph.g2o").string(), formatG2o(slam.graph()));
  std::cout << "processed " << results.size() << " frames (" << countFallbacks(results) << " with fallback odometry, "
            << countLoopClosures(results) << " loop closures)\n";
  std::vector<std::optional<CandidateTruth>> truths;
  if (dataset.hasGroundTruth()) {
    const Trajectory groundtruth = groundTruthOf(dataset, config);
    writeTum((out / "groundtruth.tum").string(), groundtruth);
    std::vector<double> timestamps;
    for (const auto& p : trajectory) timestamps.push_back(p.timestamp);
    truths = candidateTruths(slam.loopCandidates(), timestamps, groundtruth, cameraModelFrom(config.camera).groundFootprint());
    const TrajectoryMetrics metrics = evaluateTrajectory(groundtruth, trajectory).metrics;
    const LoopClosureMetrics loops = summariseLoopClosures(slam.loopCandidates(), truths);
    writeFileAtomically((out / "metrics.json").string(), runMetricsJson(metrics, loops));
    std::cout << metricsToText(metrics) << loopMetricsToText(loops);
  }
  writeFileAtomically((out / "candidates.csv").string(), formatCandidatesCsv(slam.loopCandidates(), truths));
  writeTum((out / "trajectory.tum").string(), trajectory);  // last: its presence marks a finished run
  std::cout << "results in " << out.string() << "\n";
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Run SLAM on an HD Ground list or an image folder");
  cmd->add_option("DATASET", o->dataset, "HD Ground list (.txt/.test) or image folder")->required();
  cmd->add_option("--config", o->config, "Configuration YAML, applied over camera.yaml beside the dataset");
  cmd->add_option("--out", o->out_dir, "Run folder for the results")->capture_default_str();
  cmd->add_flag("--no-loop-closure", o->no_loop_closure, "Odometry only (sets loop_closure.enabled = false)");
  cmd->add_flag("--report", o->report, "Also run odometry only into DIR/odometry and write DIR/report.html");
  cmd->callback([o]() {
    run(*o);
    if (!o->report) return;
    if (!o->no_loop_closure) {
      RunOptions odometry = *o;
      odometry.no_loop_closure = true;
      odometry.out_dir = (fs::path(o->out_dir) / "odometry").string();
      std::cout << "odometry-only run for the report:\n";
      run(odometry);
    }
    writeReport(o->out_dir, "");
  });
}

}  // namespace groundslam::apps
