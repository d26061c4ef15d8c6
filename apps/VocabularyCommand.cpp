// `groundslam vocabulary train INPUT... -o FILE`: trains a bag-of-words vocabulary for loop closure.
#include <filesystem>
#include <iostream>
#include <memory>

#include <unistd.h>

#include <opencv2/core.hpp>

#include "Commands.hpp"
#include "Progress.hpp"
#include "groundslam/bow/Vocabulary.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/VocabularyFile.hpp"

namespace fs = std::filesystem;

namespace groundslam::apps {
namespace {

struct TrainOptions {
  std::vector<std::string> inputs;
  std::string output;
  std::string config;
  int max_images = 400;
  VocabularySettings settings;
};

/// Image paths of the inputs: image files, image folders or dataset lists.
std::vector<std::string> imagePaths(const std::vector<std::string>& inputs) {
  std::vector<std::string> paths;
  for (const auto& input : inputs) {
    if (fs::is_regular_file(input) && fs::path(input).extension() != ".txt" && fs::path(input).extension() != ".test") {
      paths.push_back(input);
      continue;
    }
    for (const auto& frame : openDataset(input).frames) paths.push_back(frame.image_path);
  }
  return paths;
}

void train(const TrainOptions& o) {
  ConfigLoader loader;
  if (!o.config.empty()) loader.applyFile(o.config);
  const OrbExtractor extractor(loader.finishWithoutRequiredKeys().features);
  // The output is checked before minutes of training, not after.
  {
    std::error_code error;
    const fs::path out(o.output);
    const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
    if (fs::is_directory(out, error)) throw InputError("-o " + o.output + ": is a folder; name the vocabulary file to write");
    if (!fs::is_directory(parent, error)) throw InputError("-o " + o.output + ": the folder " + parent.string() + " does not exist");
    if (access(parent.c_str(), W_OK) != 0) throw InputError("-o " + o.output + ": cannot write into " + parent.string());
  }
  const std::vector<std::string> all = imagePaths(o.inputs);
  if (all.empty()) throw InputError("vocabulary train: the inputs hold no images");
  std::error_code error;
  for (const auto& input : o.inputs) {
    if (fs::exists(o.output, error) && fs::equivalent(o.output, input, error)) {
      throw InputError("-o " + o.output + ": is an input; choose another file");
    }
  }
  // An even sample over all inputs keeps training time bounded.
  const size_t count = std::min(all.size(), static_cast<size_t>(o.max_images));
  std::vector<cv::Mat> descriptors;
  Progress progress("extract", static_cast<int>(count));
  for (size_t i = 0; i < count; ++i) {
    const std::string& path = all[i * all.size() / count];
    const cv::Mat image = loadGrayImageAnySize(path);
    descriptors.push_back(extractor.detect(image).descriptors);
    progress.update(static_cast<int>(i + 1));
  }
  progress.finish();
  Progress clustering("k-means", 100, "%");
  const Vocabulary vocabulary =
      Vocabulary::train(descriptors, o.settings, [&](double done) { clustering.update(static_cast<int>(100.0 * done)); });
  clustering.finish();
  if (vocabulary.wordCount() < o.settings.branching) {
    size_t features = 0;
    for (const cv::Mat& d : descriptors) features += static_cast<size_t>(d.rows);
    throw InputError("vocabulary train: the " + std::to_string(count) + " images hold " + std::to_string(features) +
                     " ORB features, too few distinct ones for a vocabulary (" + std::to_string(vocabulary.wordCount()) +
                     " words); train on textured images of the floor. Nothing was written.");
  }
  writeVocabulary(o.output, vocabulary);
  std::cout << "trained " << vocabulary.wordCount() << " words (branching " << o.settings.branching << ", depth "
            << o.settings.depth << ") from " << count << " images -> " << o.output << "\n";
}

}  // namespace

void addVocabularyCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("vocabulary", "Bag-of-words vocabulary for loop closure");
  cmd->require_subcommand(1);
  auto o = std::make_shared<TrainOptions>();
  CLI::App* train_cmd = cmd->add_subcommand("train", "Train a vocabulary from images, image folders or datasets");
  train_cmd->add_option("INPUT", o->inputs, "Images, image folders or HD Ground lists")->required()->check(CLI::ExistingPath);
  train_cmd->add_option("-o,--output", o->output, "Vocabulary file to write")->required();
  train_cmd->add_option("--config", o->config, "Configuration whose `features` section extracts the descriptors");
  train_cmd->add_option("--max-images", o->max_images, "Images used, sampled evenly")->check(CLI::Range(1, 1000000))->capture_default_str();
  train_cmd->add_option("--branching", o->settings.branching, "Children per node (k)")->check(CLI::Range(2, 64))->capture_default_str();
  train_cmd->add_option("--depth", o->settings.depth, "Levels (L); up to k^L words")->check(CLI::Range(1, 8))->capture_default_str();
  train_cmd->add_option("--seed", o->settings.seed, "Seed of the k-means++ seeding")->capture_default_str();
  train_cmd->callback([o]() { train(*o); });
}

}  // namespace groundslam::apps
