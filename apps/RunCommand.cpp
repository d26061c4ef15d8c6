// `groundslam run DATASET`: runs SLAM on a sequence and writes the results into a run folder.
#include <memory>

#include "Commands.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"

namespace groundslam::apps {
namespace {

struct RunOptions {
  std::string dataset;
  std::string config;
  std::string out_dir = "runs/latest";
  bool no_loop_closure = false;
};

void run(const RunOptions& o) {
  const Dataset dataset = openDataset(o.dataset);
  std::vector<std::string> layers;
  if (dataset.camera_yaml) layers.push_back(*dataset.camera_yaml);
  if (!o.config.empty()) layers.push_back(o.config);
  const Config config = loadConfig(layers);
  (void)config;
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
