#pragma once
// Reading and writing the run configuration as YAML (docs/conventions.md). Files are applied in layers
// over the defaults; unknown keys and bad values are errors that name the file, line and key.

#include <optional>
#include <map>
#include <string>
#include <vector>

#include "groundslam/pipeline/Config.hpp"

namespace groundslam {

/// What the programs that read files take from a configuration besides the pipeline's Config: the same YAML
/// files, sections and keys, but nothing the algorithm uses.
struct InputSettings {
  std::string vocabulary;                      ///< loop_closure.vocabulary: the file; empty: the one shipped with groundslam
  std::optional<double> map_meters_per_pixel;  ///< dataset.map_meters_per_pixel: HD Ground map scale; empty: mounting_height_m / fx
};

/// Everything a configuration file sets.
struct RunSettings {
  Config config;
  InputSettings inputs;
};

/// Calls visitor(section, key, field, constraint) for every field of the settings: the configuration's
/// (visitConfigFields), then the inputs'.
template <class Settings, class Visitor>
void visitSettingsFields(Settings& s, Visitor&& v) {
  visitConfigFields(s.config, v);
  v("loop_closure", "vocabulary", s.inputs.vocabulary, Choices{});
  v("dataset", "map_meters_per_pixel", s.inputs.map_meters_per_pixel, kPositive);
}

/// The vocabulary the settings name, or the shipped one.
std::string vocabularyPath(const InputSettings& inputs);

class ConfigLoader {
 public:
  /// Applies the keys of one YAML file over what is set so far; a relative `loop_closure.vocabulary` in it
  /// is resolved against the file's folder. Throws InputError.
  void applyFile(const std::string& path);
  /// Applies YAML text; `source` names it in errors.
  void applyText(const std::string& yaml_text, const std::string& source);
  /// The settings; throws InputError naming a required key that no layer set, or the file and line of a key
  /// whose value does not fit the others (findConfigProblem).
  RunSettings finish() const;
  /// The configuration without the required-key check (for tools that need no camera).
  Config finishWithoutRequiredKeys() const { return settings_.config; }

 private:
  RunSettings settings_;
  std::map<std::string, std::string> set_keys_;  ///< "section.key" -> "file:line" that set it
  std::vector<std::string> sources_;
};

/// Loads files in order (later ones override earlier ones) and checks the required keys.
RunSettings loadConfig(const std::vector<std::string>& paths);

/// A dataset's configuration: its camera.yaml (when it has one), then the user's file (when given).
/// `calibration` (optional): an OpenCV / ROS / Kalibr calibration file whose intrinsics, image size and
/// distortion go over the camera section (io/CalibrationFile.hpp); the mount stays from the YAML files.
RunSettings loadDatasetConfig(const std::optional<std::string>& camera_yaml, const std::string& user_config,
                              const std::string& calibration = "");

/// The effective settings as YAML text: every key, or only those of the named sections.
std::string configToYaml(const RunSettings& settings, const std::vector<std::string>& only_sections = {});

}  // namespace groundslam
