// `groundslam localize MAP DATASET`: each image localized on its own on a map of an earlier run, with no
// odometry and no order (global localization, no pose prior).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "Commands.hpp"
#include "Progress.hpp"
#include "StopSignals.hpp"
#include "RunOutputs.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/MapFile.hpp"
#include "groundslam/io/RunFolder.hpp"
#include "groundslam/io/Tum.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/localization/GlobalLocalizer.hpp"
#include "groundslam/pipeline/FramePreparer.hpp"

namespace fs = std::filesystem;

namespace groundslam::apps {
namespace {

struct LocalizeOptions {
  std::string map;
  std::string dataset;
  std::string config;
  std::string out_dir;
  std::string calibration;  ///< OpenCV / ROS / Kalibr calibration: intrinsics and distortion
};

struct Localized {
  int index = 0;
  double timestamp = 0.0;
  Localization localization;
  double ms = 0.0;
};

std::string localizationsCsv(const std::vector<Localized>& rows) {
  std::string csv = "index,timestamp,status,x,y,theta,inliers,votes,ms\n";
  char line[256];
  for (const Localized& r : rows) {
    const Pose2& T = r.localization.T_map_robot;
    const bool ok = r.localization.ok();
    std::snprintf(line, sizeof(line), "%d,%.9g,%s,%.9f,%.9f,%.9f,%d,%d,%.3f\n", r.index, r.timestamp,
                  localizationStatusName(r.localization.status), ok ? T.x : 0.0, ok ? T.y : 0.0, ok ? T.theta : 0.0,
                  r.localization.inliers, r.localization.votes, r.ms);
    csv += line;
  }
  return csv;
}

/// Against ground truth: localized images within 1 cm and 1 degree, and those off by more than 5 cm. The map
/// frame is the first pose of the run that built the map, not the ground truth's frame: the two are related
/// by the SE(2) alignment of the localized positions, refitted on those within 5 cm of it (outliers cannot
/// pull it).
std::string accuracySummary(const std::vector<Localized>& rows, const Trajectory& groundtruth) {
  std::map<double, Pose2> truth;
  for (const StampedPose& p : groundtruth) truth[p.timestamp] = p.T_world_robot;
  std::vector<std::pair<Pose2, Pose2>> pairs;  // (truth, localized)
  for (const Localized& r : rows) {
    const auto it = truth.find(r.timestamp);
    if (r.localization.ok() && it != truth.end()) pairs.emplace_back(it->second, r.localization.T_map_robot);
  }
  if (pairs.size() < 2) return "against ground truth: fewer than 2 localized images with ground truth, nothing to compare\n";
  Pose2 T_truth_map;
  for (int round = 0; round < 3; ++round) {
    std::vector<Eigen::Vector2d> from, to;
    for (const auto& [t, l] : pairs) {
      if (round > 0 && ((T_truth_map * l).translation() - t.translation()).norm() > 0.05) continue;
      from.push_back(l.translation());
      to.push_back(t.translation());
    }
    if (from.size() >= 2) T_truth_map = alignSE2(from, to);
  }
  int within = 0, off = 0;
  for (const auto& [t, l] : pairs) {
    const Pose2 error = t.inverse() * (T_truth_map * l);
    if (error.translation().norm() <= 0.01 && std::abs(error.theta) <= M_PI / 180.0) ++within;
    if (error.translation().norm() > 0.05) ++off;
  }
  char text[320];
  std::snprintf(text, sizeof(text),
                "against ground truth (map frame aligned to it): %d of %zu localized images within 1 cm and 1 deg, %d off by more than 5 cm\n",
                within, pairs.size(), off);
  return text;
}

void localize(const LocalizeOptions& o) {
  const Dataset dataset = openDataset(o.dataset);
  if (dataset.isVideo()) throw InputError(dataset.source + ": `localize` reads image datasets (a video or camera: groundslam run)");
  const RunSettings settings = loadDatasetConfig(dataset.camera_yaml, o.config, o.calibration);
  const Config& config = settings.config;
  const auto vocabulary = loadVocabulary(settings.inputs);
  const FeatureMap map = readMap(o.map, vocabulary);
  const std::string target = o.out_dir.empty() ? newRunFolderName("runs") : o.out_dir;
  RunFolder folder(target, {o.dataset, o.config, dataset.camera_yaml.value_or(""), o.map, vocabularyPath(settings.inputs)});
  installStopHandlers();
  writeNewFile(folder.path("config.yaml"), configToYaml(settings));
  const FramePreparer preparer(config);
  // Each image on its own: no odometry shows whether the floor repeats, so the votes are always compared.
  LocalizationSettings localization = config.localization;
  localization.unrepeated_max_vote_ratio = localization.max_vote_ratio;
  std::vector<Localized> rows;
  Trajectory localized;
  Progress progress("localize", static_cast<int>(dataset.frames.size()));
  for (size_t i = 0; i < dataset.frames.size() && stopSignal() == 0; ++i) {
    const DatasetFrame& frame = dataset.frames[i];
    const DecodedImage decoded = loadGrayImageForExtraction(frame.image_path, config.camera.image_width,
                                                            config.camera.image_height, preparer.decoderReduction());
    const PreparedFrame prepared = preparer.prepare(decoded.image, frame.timestamp, decoded.reduced_by);
    const auto start = std::chrono::steady_clock::now();
    const Localization l = localizeGlobally(map, prepared.features, localization, config.odometry);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    rows.push_back({static_cast<int>(i), frame.timestamp, l, ms});
    if (l.ok()) localized.push_back({frame.timestamp, l.T_map_robot});
    progress.update(static_cast<int>(i + 1));
  }
  progress.finish();
  writeNewFile(folder.path("localizations.csv"), localizationsCsv(rows));
  writeNewFile(folder.path("localized.tum"), formatTum(localized));
  std::vector<double> ms;
  for (const Localized& r : rows) ms.push_back(r.ms);
  std::sort(ms.begin(), ms.end());
  std::cout << "localized " << localized.size() << " of " << rows.size() << " images on a map of " << map.features().size()
            << " features (median " << (ms.empty() ? 0.0 : ms[ms.size() / 2]) << " ms per localization, decoding and ORB excluded)\n";
  if (dataset.hasGroundTruth()) {
    const Trajectory groundtruth = groundTruthOf(dataset, config.camera, settings.inputs.map_meters_per_pixel);
    writeNewFile(folder.path("groundtruth.tum"), formatTum(groundtruth));
    std::cout << accuracySummary(rows, groundtruth);
  }
  const bool interrupted = rows.size() < dataset.frames.size();
  writeNewFile(folder.path("run.yaml"), runStatusYaml("localize", rows.size(), dataset.frames.size(), o.dataset, vocabularyPath(settings.inputs)));
  const std::string where = interrupted ? folder.commitPartial() : folder.commit();
  if (o.out_dir.empty()) pointLatestAt("runs", where);
  std::cout << "results in " << where << "\n";
  if (interrupted) throw Interrupted{stopSignal()};
}

}  // namespace

void addLocalizeCommand(CLI::App& app) {
  auto o = std::make_shared<LocalizeOptions>();
  CLI::App* cmd = app.add_subcommand("localize", "Localize every image of a dataset on a map of an earlier run, each on its own");
  cmd->add_option("MAP", o->map, "Map file (map.gsmap written by groundslam run)")->required()->check(CLI::ExistingFile);
  cmd->add_option("DATASET", o->dataset, "HD Ground list (.txt/.test), a .txt list of image paths, or an image folder")->required();
  cmd->add_option("--config", o->config, "Configuration YAML, applied over camera.yaml beside the dataset");
  cmd->add_option("--calibration", o->calibration, "Camera calibration (OpenCV, ROS camera_info, Kalibr): intrinsics and distortion")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out_dir, "Folder for localizations.csv and localized.tum (default: a new folder runs/YYYYmmdd_HHMMSS)");
  cmd->callback([o]() { localize(*o); });
}

}  // namespace groundslam::apps
