// `groundslam evaluate`: the paper's metrics and standard trajectory errors, for two TUM files or a run
// folder (which adds loop-closure precision, recall and transform errors).
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

void evaluateFiles(const EvaluateOptions& o) {
  const TrajectoryMetrics metrics =
      evaluateTrajectory(readTum(o.inputs[0]), readTum(o.inputs[1]), o.max_time_difference).metrics;
  std::cout << metricsToText(metrics);
  if (!o.json.empty()) writeFileAtomically(o.json, metricsToJson(metrics));
}

void evaluateRun(const EvaluateOptions& o) {
  const fs::path run(o.inputs[0]);
  if (!fs::exists(run / "groundtruth.tum")) throw InputError((run / "groundtruth.tum").string() + ": no ground truth in this run folder");
  const Trajectory groundtruth = readTum((run / "groundtruth.tum").string());
  const Trajectory estimate = readTum((run / "trajectory.tum").string());
  const TrajectoryMetrics metrics = evaluateTrajectory(groundtruth, estimate, o.max_time_difference).metrics;
  std::cout << metricsToText(metrics);
  LoopClosureMetrics loops;
  if (fs::exists(run / "candidates.csv")) {
    const Config config = loadConfig({(run / "config.yaml").string()});
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
