// `groundslam evaluate GROUNDTRUTH ESTIMATE`: the paper's metrics and standard trajectory errors.
#include <memory>

#include "Commands.hpp"

namespace groundslam::apps {

void addEvaluateCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("evaluate", "Compare an estimated trajectory with ground truth");
  (void)cmd;
}

}  // namespace groundslam::apps
