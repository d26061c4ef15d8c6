// `groundslam evaluate`: the paper's metrics and standard trajectory errors, for two TUM files or a run
// folder (which adds loop-closure precision, recall and transform errors).
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>

#include "Commands.hpp"
#include "RunOutputs.hpp"
#include "groundslam/eval/LoopClosureMetrics.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/RunFiles.hpp"
#include "groundslam/io/Tum.hpp"
#include "groundslam/pipeline/Slam.hpp"

namespace fs = std::filesystem;

namespace groundslam::apps {
namespace {

struct EvaluateOptions {
  std::vector<std::string> inputs;
  std::string json;
  double max_time_difference = 1e-3;
};

/// The metrics of an estimate against ground truth; "nothing to compare" is an error, not a perfect score.
TrajectoryMetrics compare(const Trajectory& groundtruth, const std::string& groundtruth_name, const Trajectory& estimate,
                          const std::string& estimate_name, double max_time_difference) {
  if (groundtruth.empty()) throw InputError(groundtruth_name + ": no poses (nothing to compare)");
  if (estimate.empty()) throw InputError(estimate_name + ": no poses (nothing to compare)");
  const TrajectoryMetrics metrics = evaluateTrajectory(groundtruth, estimate, max_time_difference).metrics;
  if (metrics.paired_frames == 0) {
    const auto span = [](const Trajectory& t) {
      const auto [lo, hi] = std::minmax_element(t.begin(), t.end(), [](const auto& a, const auto& b) { return a.timestamp < b.timestamp; });
      return std::to_string(t.size()) + " poses, t in [" + std::to_string(lo->timestamp) + ", " + std::to_string(hi->timestamp) + "]";
    };
    throw InputError("no pose of " + estimate_name + " (" + span(estimate) + ") has a timestamp within " +
                     std::to_string(max_time_difference) + " s of one of " + groundtruth_name + " (" + span(groundtruth) +
                     "): nothing to compare");
  }
  return metrics;
}

void evaluateFiles(const EvaluateOptions& o) {
  const TrajectoryMetrics metrics =
      compare(readTum(o.inputs[0]), o.inputs[0], readTum(o.inputs[1]), o.inputs[1], o.max_time_difference);
  std::cout << metricsToText(metrics);
  if (!o.json.empty()) writeFileAtomically(o.json, metricsToJson(metrics));
}

void evaluateRun(const EvaluateOptions& o) {
  const fs::path run(o.inputs[0]);
  if (!fs::exists(run / "groundtruth.tum")) throw InputError((run / "groundtruth.tum").string() + ": no ground truth in this run folder");
  const Trajectory groundtruth = readTum((run / "groundtruth.tum").string());
  Trajectory estimate = readTum((run / "trajectory.tum").string());
  if (fs::exists(run / "frames.csv")) markUnmeasuredPoses((run / "frames.csv").string(), estimate);
  const TrajectoryMetrics metrics = compare(groundtruth, (run / "groundtruth.tum").string(), estimate,
                                            (run / "trajectory.tum").string(), o.max_time_difference);
  std::cout << metricsToText(metrics);
  LoopClosureMetrics loops;
  if (fs::exists(run / "candidates.csv")) {
    const Config config = loadConfig({(run / "config.yaml").string()}).config;
    const auto candidates = readCandidatesCsv((run / "candidates.csv").string());
    std::vector<double> timestamps;
    for (const auto& p : estimate) timestamps.push_back(p.timestamp);
    loops = summariseLoopClosures(
        candidates, candidateTruths(candidates, timestamps, groundtruth, cameraModelFrom(config.camera).groundFootprint()));
    std::cout << loopMetricsToText(loops);
  }
  if (!o.json.empty()) writeFileAtomically(o.json, runMetricsJson(metrics, loops));
}

}  // namespace

void addEvaluateCommand(CLI::App& app) {
  auto o = std::make_shared<EvaluateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "evaluate", "Compare an estimate with ground truth: GROUNDTRUTH.tum ESTIMATE.tum, or a run folder");
  cmd->add_option("INPUTS", o->inputs, "GROUNDTRUTH.tum ESTIMATE.tum, or RUN_DIR")->required()->expected(1, 2)->check(CLI::ExistingPath);
  cmd->add_option("--json", o->json, "Also write the metrics as JSON to this file");
  cmd->add_option("--max-time-diff", o->max_time_difference, "Largest timestamp difference of a pair, seconds")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->callback([o]() {
    for (const auto& input : o->inputs) {
      if (!o->json.empty() && fs::exists(o->json) && fs::equivalent(o->json, input)) {
        throw InputError("--json " + o->json + ": is an input; choose another file");
      }
    }
    if (o->inputs.size() == 2) {
      evaluateFiles(*o);
    } else if (fs::is_directory(o->inputs[0])) {
      evaluateRun(*o);
    } else {
      throw InputError(o->inputs[0] + ": expected a run folder, or two TUM files");
    }
  });
}

}  // namespace groundslam::apps
