// Runs groundslam on a folder of ground images (or an HD Ground list) and prints the trajectory as TUM
// lines (timestamp x y z qx qy qz qw). Build it against an installed groundslam: see CMakeLists.txt here.
#include <iostream>
#include <memory>

#include <groundslam/groundslam.hpp>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: run_folder DATASET [CONFIG.yaml]\n";
    return 1;
  }
  try {
    const groundslam::Dataset dataset = groundslam::openDataset(argv[1]);
    // The dataset's camera.yaml, the optional file over it: the pipeline's config and the vocabulary's path.
    const groundslam::RunSettings settings = groundslam::loadDatasetConfig(dataset.camera_yaml, argc > 2 ? argv[2] : "");
    auto vocabulary = std::make_shared<const groundslam::Vocabulary>(
        groundslam::readVocabulary(groundslam::vocabularyPath(settings.inputs)));
    groundslam::Slam slam(settings.config, vocabulary);
    const groundslam::RunnerOutput output = groundslam::runDataset(dataset, settings.config, slam);
    std::cout << groundslam::formatTum(slam.trajectory());
    std::cerr << "run_folder: " << output.results.size() << " frames\n";
  } catch (const std::exception& e) {
    std::cerr << "run_folder: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
