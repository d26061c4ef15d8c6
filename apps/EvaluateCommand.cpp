// `groundslam evaluate GROUNDTRUTH ESTIMATE`: the paper's metrics and standard trajectory errors.
#include <iostream>
#include <memory>

#include "Commands.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/Tum.hpp"

namespace groundslam::apps {
namespace {

struct EvaluateOptions {
  std::string groundtruth;
  std::string estimate;
  std::string json;
  double max_time_difference = 1e-3;
};

void evaluate(const EvaluateOptions& o) {
  const TrajectoryMetrics metrics =
      evaluateTrajectory(readTum(o.groundtruth), readTum(o.estimate), o.max_time_difference).metrics;
  std::cout << metricsToText(metrics);
  if (!o.json.empty()) writeFileAtomically(o.json, metricsToJson(metrics));
}

}  // namespace

void addEvaluateCommand(CLI::App& app) {
  auto o = std::make_shared<EvaluateOptions>();
  CLI::App* cmd = app.add_subcommand("evaluate", "Compare an estimated trajectory with ground truth (TUM files)");
  cmd->add_option("GROUNDTRUTH", o->groundtruth, "Ground-truth TUM file")->required();
  cmd->add_option("ESTIMATE", o->estimate, "Estimated TUM file")->required();
  cmd->add_option("--json", o->json, "Also write the metrics as JSON to this file");
  cmd->add_option("--max-time-diff", o->max_time_difference, "Largest timestamp difference of a pair, seconds")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->callback([o]() { evaluate(*o); });
}

}  // namespace groundslam::apps
