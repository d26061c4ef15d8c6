// `groundslam run DATASET`: runs SLAM on a sequence and writes the results into a run folder.
#include <filesystem>
#include <iostream>
#include <memory>

#include "Commands.hpp"
#include "Progress.hpp"
#include "RunOutputs.hpp"
#include "StopSignals.hpp"
#include "groundslam/eval/LoopClosureMetrics.hpp"
#include "groundslam/eval/NumberText.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/DatasetRunner.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/MapFile.hpp"
#include "groundslam/io/RunFolder.hpp"
#include "groundslam/io/RunFiles.hpp"
#include "groundslam/io/Tum.hpp"
#include "groundslam/pipeline/Slam.hpp"

namespace fs = std::filesystem;

namespace groundslam::apps {
namespace {

struct RunOptions {
  std::string dataset;
  std::string config;
  std::string out_dir;  ///< empty: a new folder under runs/, with runs/latest pointing at it
  std::string map;      ///< a prior map (map.gsmap of an earlier run): the session localizes and tracks on it
  bool no_loop_closure = false;
  bool report = false;
  long long start = 0, stop = -1, every = 1;  ///< frames start, start + every, ... before stop (-1: the end)
  std::string calibration;  ///< OpenCV / ROS / Kalibr calibration file: the intrinsics and distortion
  int camera = -1;          ///< a camera device instead of DATASET (-1: none)
};

/// How far a run got: every frame, or the frames before a stop signal.
struct RunProgress {
  size_t processed = 0;
  size_t total = 0;
  bool interrupted() const { return processed < total; }
};

RunSettings loadRunSettings(const Dataset& dataset, const RunOptions& o) {
  RunSettings settings = loadDatasetConfig(dataset.camera_yaml, o.config, o.calibration);
  if (o.no_loop_closure) settings.config.loop_closure.enabled = false;
  return settings;
}

/// Runs the frames through the pipeline until the last one or a stop signal, with a progress line on a
/// terminal. The next frames are decoded and their features extracted on other threads (a FramePreparer
/// each) while the current one goes through the back end, so both cores stay busy.
/// The library's runner, with the console's progress line and Ctrl-C.
std::vector<FrameResult> processAll(const Dataset& dataset, const Config& config, Slam& slam, std::vector<double>& load_ms) {
  Progress progress("run", static_cast<int>(dataset.frames.size()));
  int done = 0;
  RunnerCallbacks callbacks;
  callbacks.on_frame = [&](const FrameResult&) { progress.update(++done); };
  callbacks.should_stop = [] { return stopSignal() != 0; };
  RunnerOutput output = runDataset(dataset, config, slam, callbacks);
  progress.finish();
  load_ms = std::move(output.load_ms);
  return std::move(output.results);
}

/// Runs SLAM on the dataset and writes every result file into `folder`, a fresh folder of this run's own.
RunProgress runInto(const std::string& folder, const RunOptions& o, const Dataset& dataset, const RunSettings& settings) {
  const auto file = [&](const char* name) { return (fs::path(folder) / name).string(); };
  const Config& config = settings.config;
  const std::shared_ptr<const Vocabulary> vocabulary = config.loop_closure.enabled ? loadVocabulary(settings.inputs) : nullptr;
  Slam slam(config, vocabulary);
  if (!o.map.empty()) {
    if (!vocabulary) throw InputError("--map " + o.map + ": a prior map needs loop closure (drop --no-loop-closure)");
    slam.usePriorMap(readMap(o.map, vocabulary));
  }
  writeNewFile(file("config.yaml"), configToYaml(settings));
  std::vector<double> load_ms;
  std::vector<FrameResult> results = processAll(dataset, config, slam, load_ms);
  for (FrameResult& r : results) {  // as solved over the whole run
    r.mount = slam.finalMount(r.index);
    r.odometry = slam.finalOdometry(r.index, r.odometry);
  }
  // A video's or camera's length is what was read (an interrupted stream is still a complete run of it).
  const size_t total = dataset.isVideo() ? results.size() : dataset.frames.size();
  const RunProgress progress{results.size(), total};
  const Trajectory trajectory = slam.trajectory();
  writeNewFile(file("frames.csv"), formatFramesCsv(results, load_ms));
  writeNewFile(file("loop_closures.csv"), formatLoopClosuresCsv(slam.loopCandidates()));
  writeNewFile(file("graph.g2o"), formatG2o(slam.graph()));
  if (slam.featureMap()) writeNewFile(file("map.gsmap"), formatMap(*slam.featureMap(), slam.mapSegment()));
  const auto measured = std::count_if(trajectory.begin(), trajectory.end(), [](const StampedPose& p) { return p.measured; });
  std::cout << "timestamps from " << dataset.timestamps_from << "\n";
  std::cout << "processed " << results.size() << " of " << total << " frames: " << measured << " measured, "
            << countStatus(results, FrameStatus::low_overlap) << " measured at low overlap (less certain), "
            << countStatus(results, FrameStatus::aligned) << " measured by aligning the images (too few features; less certain), "
            << countStatus(results, FrameStatus::unconfirmed) << " measured from few keypoints the images did not confirm (less certain), "
            << countStatus(results, FrameStatus::uncertain) << " measured with a covariance too wide for ok (less certain), "
            << countStatus(results, FrameStatus::sharp_turn) << " measured across a sharp turn (translation less certain), "
            << countStatus(results, FrameStatus::gap) << " measured across dropped frames (less certain), "
            << countStatus(results, FrameStatus::fallback) << " with fallback odometry (pose assumed from earlier motion), "
            << countStatus(results, FrameStatus::lost) << " lost (tracking lost, not yet relocalized), " << countStatus(results, FrameStatus::relocalized)
            << " relocalizations, " << countLoopClosures(results) << " loop closures\n";
  if (const auto rocking = slam.mountRocking()) {
    std::cout << "camera mount solved over the whole run: tilt " << textNumber(rocking->tilt.sigma, 3, 180.0 / M_PI)
              << " deg RMS per axis (frame-to-frame correlation " << textNumber(rocking->tilt.correlation, 2) << "), height "
              << textNumber(rocking->height.sigma, 2, 1000.0) << " mm RMS (correlation " << textNumber(rocking->height.correlation, 2)
              << ")" << (slam.mountSmoothed() ? "\n" : ": not used (the frames keep the mounts they were processed with)\n");
  }

  std::vector<std::optional<CandidateTruth>> truths;
  const Trajectory groundtruth = dataset.hasGroundTruth() ? groundTruthOf(dataset, config.camera, settings.inputs.map_meters_per_pixel) : Trajectory{};
  if (dataset.hasGroundTruth() && groundtruth.empty()) {
    std::cout << "no metrics: every pose line of " << dataset.source << " is marked unreliable\n";
  } else if (!groundtruth.empty()) {
    writeNewFile(file("groundtruth.tum"), formatTum(groundtruth));
    std::vector<double> timestamps;
    for (const auto& p : trajectory) timestamps.push_back(p.timestamp);
    truths = candidateTruths(slam.loopCandidates(), timestamps, groundtruth, cameraModelFrom(config.camera).groundFootprint());
    const TrajectoryMetrics metrics = evaluateTrajectory(groundtruth, trajectory).metrics;
    const LoopClosureMetrics loops = summariseLoopClosures(slam.loopCandidates(), truths);
    writeNewFile(file("metrics.json"), runMetricsJson(metrics, loops));
    std::cout << metricsToText(metrics) << loopMetricsToText(loops);
  }
  writeNewFile(file("candidates.csv"), formatCandidatesCsv(slam.loopCandidates(), truths));
  if (config.loop_closure.enabled) writeNewFile(file("relocalizations.csv"), formatRelocalizationsCsv(slam.relocalizationAttempts()));
  writeNewFile(file("trajectory.tum"), formatTum(trajectory));
  writeNewFile(file("run.yaml"), runStatusYaml("run", progress.processed, progress.total, o.dataset,
                                                  config.loop_closure.enabled ? vocabularyPath(settings.inputs) : ""));  // last: its status says whether the run finished
  return progress;
}

/// Every file the run reads: none may lie inside the output folder that the run replaces.
std::vector<std::string> runInputs(const RunOptions& o, const Dataset& dataset, const RunSettings& settings) {
  std::vector<std::string> inputs = {o.dataset, o.config, dataset.camera_yaml.value_or(""), o.map};
  if (settings.config.loop_closure.enabled) inputs.push_back(vocabularyPath(settings.inputs));
  return inputs;
}

void run(const RunOptions& o) {
  if (o.dataset.empty() == (o.camera < 0)) throw InputError("give either DATASET or --camera N");
  Dataset dataset = o.camera >= 0 ? openCameraDevice(o.camera, std::nullopt) : openDataset(o.dataset);
  selectFrames(dataset, o.start, o.stop, o.every);
  const RunSettings settings = loadRunSettings(dataset, o);
  const std::string target = o.out_dir.empty() ? newRunFolderName("runs") : o.out_dir;
  RunFolder folder(target, runInputs(o, dataset, settings));
  installStopHandlers();
  RunProgress progress = runInto(folder.stagingFolder(), o, dataset, settings);
  if (o.report && !progress.interrupted()) {
    if (!o.no_loop_closure) {
      RunOptions odometry = o;
      odometry.no_loop_closure = true;
      odometry.map.clear();
      const std::string odometry_folder = folder.path("odometry");
      fs::create_directory(odometry_folder);
      std::cout << "odometry-only run for the report:\n";
      const RunProgress odometry_progress = runInto(odometry_folder, odometry, dataset, loadRunSettings(dataset, odometry));
      if (odometry_progress.interrupted()) progress.processed = std::min(progress.processed, odometry_progress.processed);
    }
    if (!progress.interrupted() && stopSignal() == 0) writeReport(folder.stagingFolder(), "");
  }
  if (progress.interrupted()) {
    const std::string where = folder.commitPartial();
    std::cout << "interrupted: partial results (" << progress.processed << " of " << progress.total
              << " frames; run.yaml says so) in " << where << "\n";
    throw Interrupted{stopSignal()};
  }
  const std::string where = folder.commit();
  if (o.out_dir.empty() && !pointLatestAt("runs", where)) {
    std::cout << "note: runs/latest is not a symbolic link, left as it is\n";
  }
  std::cout << "results in " << where << (o.out_dir.empty() ? " (runs/latest)" : "") << "\n";
  if (stopSignal() != 0) {
    std::cout << "interrupted after the last frame: the results are complete" << (o.report ? ", the report was not drawn" : "") << "\n";
    throw Interrupted{stopSignal()};
  }
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Run SLAM on an HD Ground list or an image folder");
  cmd->add_option("DATASET", o->dataset, "HD Ground list (.txt/.test), a .txt list of image paths, an image folder or a video file");
  cmd->add_option("--camera", o->camera, "Read a camera device (OpenCV index) instead of DATASET; its calibration and mount from --config / --calibration");
  cmd->add_option("--config", o->config, "Configuration YAML, applied over camera.yaml beside the dataset");
  cmd->add_option("--out", o->out_dir,
                  "Run folder for the results; replaced only when the run succeeds, refused when it holds other files "
                  "(default: a new folder runs/YYYYmmdd_HHMMSS, with runs/latest pointing at it)");
  cmd->add_option("--map", o->map, "Prior map (map.gsmap of an earlier run): localize on it, track and close loops against it; "
                                    "poses come out in its frame and DIR/map.gsmap is the merged map")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--no-loop-closure", o->no_loop_closure, "Odometry only (sets loop_closure.enabled = false)");
  cmd->add_option("--calibration", o->calibration,
                  "Camera calibration (OpenCV FileStorage YAML/XML, ROS camera_info, Kalibr camchain): intrinsics and distortion; "
                  "the mount stays from camera.yaml / --config")->check(CLI::ExistingFile);
  cmd->add_option("--start", o->start, "First frame (index in the dataset)")->capture_default_str();
  cmd->add_option("--stop", o->stop, "Stop before this frame (-1: the last frame)")->capture_default_str();
  cmd->add_option("--every", o->every, "Every Nth frame from --start")->capture_default_str();
  cmd->add_flag("--report", o->report, "Also run odometry only into DIR/odometry and write DIR/report.html");
  cmd->callback([o]() { run(*o); });
}

}  // namespace groundslam::apps
