#include "groundslam/io/ConfigYaml.hpp"

#include "groundslam/io/CalibrationFile.hpp"
#include "groundslam/io/ConfigNames.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <type_traits>

#include <yaml-cpp/yaml.h>

#include "groundslam/io/DataFiles.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"

namespace fs = std::filesystem;

namespace groundslam {
namespace {

/// The line (from 1) of a document marker (`---` or `...`) that follows content, 0 when there is none:
/// YAML::Load would read the first document and silently drop the rest.
int secondDocumentLine(const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  bool content = false;
  for (int number = 1; std::getline(lines, line); ++number) {
    const bool marker = (line.rfind("---", 0) == 0 || line.rfind("...", 0) == 0) &&
                        (line.size() == 3 || line[3] == ' ' || line[3] == '\t' || line[3] == '\r');
    if (marker && content) return number;
    const auto first = line.find_first_not_of(" \t\r");
    if (!marker && first != std::string::npos && line[first] != '#') content = true;
  }
  return 0;
}

/// An integer field's range, narrowed to what an int holds.
Range integerRange(Range range) {
  range.min = std::max(range.min, static_cast<double>(std::numeric_limits<int>::min()));
  range.max = std::min(range.max, static_cast<double>(std::numeric_limits<int>::max()));
  return range;
}

std::string where(const std::string& source, const YAML::Node& node) {
  return source + ":" + std::to_string(node.Mark().line + 1);
}

[[noreturn]] void fail(const std::string& source, const YAML::Node& node, const std::string& key,
                       const std::string& what) {
  throw InputError(where(source, node) + ": key '" + key + "': " + what);
}

/// Reads the fields present in one parsed YAML document into a Config.
class FieldReader {
 public:
  FieldReader(const YAML::Node& root, const std::string& source, std::map<std::string, std::string>& set_keys)
      : root_(root), source_(source), set_keys_(set_keys) {}

  template <class T, class Constraint>
  void operator()(const char* section, const char* key, T& field, const Constraint& constraint) {
    known_[section].insert(key);
    const YAML::Node sec = root_[section];
    if (!sec || !sec.IsMap()) return;
    const YAML::Node node = sec[key];
    if (!node) return;
    const std::string name = std::string(section) + "." + key;
    read(node, name, field, constraint);
    set_keys_[name] = where(source_, node);
  }

  /// Unknown, duplicate or non-text keys are errors: yaml-cpp would silently read the first of two equal keys.
  void rejectUnknownKeys() const {
    std::set<std::string> sections;
    for (const auto& section : root_) {
      const std::string name = keyName(section.first, "");
      const auto known = known_.find(name);
      if (known == known_.end()) fail(source_, section.first, name, "unknown section");
      if (!sections.insert(name).second) fail(source_, section.first, name, "section given twice");
      if (section.second.IsNull()) continue;
      if (!section.second.IsMap()) fail(source_, section.second, name, "expected a mapping");
      std::set<std::string> keys;
      for (const auto& entry : section.second) {
        const std::string key = name + "." + keyName(entry.first, name + ".");
        if (!known->second.count(key.substr(name.size() + 1))) fail(source_, entry.first, key, "unknown key");
        if (!keys.insert(key).second) fail(source_, entry.first, key, "key given twice");
      }
    }
  }

 private:
  std::string keyName(const YAML::Node& key, const std::string& prefix) const {
    if (!key.IsScalar()) fail(source_, key, prefix + "?", "a key must be a plain name, not a list or mapping");
    return key.Scalar();
  }

  double number(const YAML::Node& node, const std::string& name) const {
    if (!node.IsScalar()) fail(source_, node, name, "expected a number");
    try {
      return node.as<double>();
    } catch (const YAML::Exception&) {
      fail(source_, node, name, "expected a number, got '" + node.Scalar() + "'");
    }
  }

  void checkRange(const YAML::Node& node, const std::string& name, double value, const Range& range) const {
    if (!std::isfinite(value)) fail(source_, node, name, "'" + node.Scalar() + "' is not a finite number");
    if (const auto problem = rangeProblem(value, range)) fail(source_, node, name, *problem);
  }

  void read(const YAML::Node& node, const std::string& name, double& field, const Range& range) const {
    field = number(node, name);
    checkRange(node, name, field, range);
  }

  void read(const YAML::Node& node, const std::string& name, int& field, const Range& range) const {
    const double value = number(node, name);
    if (!std::isfinite(value) || value != std::floor(value)) {
      fail(source_, node, name, "expected an integer, got '" + node.Scalar() + "'");
    }
    checkRange(node, name, value, integerRange(range));  // in int's range before the conversion
    field = static_cast<int>(value);
  }

  void read(const YAML::Node& node, const std::string& name, std::string& field, const Choices& choices) const {
    if (!node.IsScalar()) fail(source_, node, name, "expected a string");
    const std::string value = node.Scalar();
    if (!choices.empty() && std::find(choices.begin(), choices.end(), value) == choices.end()) {
      std::string allowed;
      for (const auto& choice : choices) allowed += (allowed.empty() ? "" : ", ") + choice;
      fail(source_, node, name, "'" + value + "' is not one of: " + allowed);
    }
    field = value;
  }

  template <class Enum>
  void read(const YAML::Node& node, const std::string& name, Enum& field, const OneOfNames&) const {
    if (!node.IsScalar()) fail(source_, node, name, "expected a string");
    const std::optional<Enum> value = valueNamed<Enum>(node.Scalar());
    if (!value) fail(source_, node, name, "'" + node.Scalar() + "' is not one of: " + allowedNames<Enum>());
    field = *value;
  }

  void read(const YAML::Node& node, const std::string& name, bool& field, const Range&) const {
    if (!node.IsScalar()) fail(source_, node, name, "expected true or false");
    try {
      field = node.as<bool>();
    } catch (const YAML::Exception&) {
      fail(source_, node, name, "expected true or false, got '" + node.Scalar() + "'");
    }
  }

  template <size_t N>
  void read(const YAML::Node& node, const std::string& name, std::array<double, N>& field, const Range& range) const {
    if (!node.IsSequence() || node.size() != N) {
      fail(source_, node, name, "expected a list of " + std::to_string(N) + " numbers");
    }
    for (size_t i = 0; i < N; ++i) read(node[i], name, field[i], range);
  }

  template <class T>
  void read(const YAML::Node& node, const std::string& name, std::optional<T>& field, const Range& range) const {
    if (node.IsNull()) {
      field.reset();
      return;
    }
    T value{};
    read(node, name, value, range);
    field = value;
  }

  const YAML::Node& root_;
  const std::string& source_;
  std::map<std::string, std::string>& set_keys_;
  std::map<std::string, std::set<std::string>> known_;
};

/// Writes every field into a YAML emitter, grouped by section: sections in the order they are first visited,
/// each with its keys in the order visited.
class FieldWriter {
 public:
  FieldWriter(YAML::Emitter& out, const std::vector<std::string>& only_sections)
      : out_(out), only_sections_(only_sections) {}

  template <class T, class Constraint>
  void operator()(const char* section, const char* key, const T& field, const Constraint&) {
    if (!only_sections_.empty() &&
        std::find(only_sections_.begin(), only_sections_.end(), section) == only_sections_.end()) {
      return;
    }
    auto found = std::find_if(sections_.begin(), sections_.end(), [&](const auto& s) { return s.first == section; });
    if (found == sections_.end()) found = sections_.insert(sections_.end(), {section, {}});
    found->second.push_back([this, key, &field] {
      out_ << YAML::Key << key << YAML::Value;
      write(field);
    });
  }

  /// Emits the sections collected; the fields visited must still be alive.
  void close() {
    for (const auto& [section, keys] : sections_) {
      out_ << YAML::Key << section << YAML::Value << YAML::BeginMap;
      for (const auto& emit : keys) emit();
      out_ << YAML::EndMap;
    }
  }

 private:
  void write(double value) {
    // The shortest text that reads back to the same double: 0.7, not 0.69999999999999996.
    char text[64];
    const auto end = std::to_chars(text, text + sizeof(text), value).ptr;
    out_ << std::string(text, end);
  }
  void write(int value) { out_ << value; }
  void write(bool value) { out_ << value; }
  void write(const std::string& value) { out_ << value; }
  template <class Enum, class = std::enable_if_t<std::is_enum_v<Enum>>>
  void write(Enum value) {
    out_ << nameOf(value);
  }
  template <size_t N>
  void write(const std::array<double, N>& values) {
    out_ << YAML::Flow << YAML::BeginSeq;
    for (double v : values) out_ << v;
    out_ << YAML::EndSeq;
  }
  template <class T>
  void write(const std::optional<T>& value) {
    if (value) {
      write(*value);
    } else {
      out_ << YAML::Null;
    }
  }

  YAML::Emitter& out_;
  const std::vector<std::string>& only_sections_;
  std::vector<std::pair<std::string, std::vector<std::function<void()>>>> sections_;
};

}  // namespace

void ConfigLoader::applyText(const std::string& yaml_text, const std::string& source) {
  if (const int line = secondDocumentLine(yaml_text)) {
    throw InputError(source + ":" + std::to_string(line) + ": a second YAML document; a configuration file holds one");
  }
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);  // not LoadAll: yaml-cpp 0.7's LoadAll never returns on some broken inputs
  } catch (const YAML::Exception& e) {
    throw InputError(source + ":" + std::to_string(e.mark.line + 1) + ": invalid YAML: " + e.msg);
  }
  sources_.push_back(source);
  if (root.IsNull()) return;
  if (!root.IsMap()) throw InputError(where(source, root) + ": expected a YAML mapping of sections (camera:, features:, ...)");
  try {
    FieldReader reader(root, source, set_keys_);
    visitSettingsFields(settings_, reader);
    reader.rejectUnknownKeys();
  } catch (const YAML::Exception& e) {
    throw InputError(source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

void ConfigLoader::applyFile(const std::string& path) {
  std::error_code error;
  if (!fs::exists(path, error)) throw InputError(path + ": no such configuration file");
  if (!fs::is_regular_file(path, error)) throw InputError(path + ": not a configuration file (a folder?)");
  const std::string before = settings_.inputs.vocabulary;
  applyText(readTextFile(path), path);
  // A vocabulary named in a file is found beside that file, wherever the command runs.
  std::string& vocabulary = settings_.inputs.vocabulary;
  if (vocabulary != before && !vocabulary.empty() && fs::path(vocabulary).is_relative()) {
    vocabulary = fs::absolute(fs::path(path).parent_path() / vocabulary).lexically_normal().string();
  }
}

RunSettings ConfigLoader::finish() const {
  for (const auto& key : requiredConfigKeys()) {
    if (set_keys_.count(key)) continue;
    std::string sources;
    for (const auto& s : sources_) sources += (sources.empty() ? "" : ", ") + s;
    throw InputError("missing required key '" + key + "'" +
                     (sources.empty() ? std::string(" (no configuration file given)") : " in " + sources));
  }
  if (const std::optional<ConfigProblem> problem = findConfigProblem(settings_.config)) {
    const auto set_at = set_keys_.find(problem->key);
    const std::string place = set_at != set_keys_.end() ? set_at->second : "default value";
    throw InputError(place + ": key '" + problem->key + "': " + problem->message);
  }
  return settings_;
}

std::string vocabularyPath(const InputSettings& inputs) {
  return inputs.vocabulary.empty() ? defaultVocabularyPath() : inputs.vocabulary;
}

RunSettings loadConfig(const std::vector<std::string>& paths) {
  ConfigLoader loader;
  for (const auto& path : paths) loader.applyFile(path);
  return loader.finish();
}

RunSettings loadDatasetConfig(const std::optional<std::string>& camera_yaml, const std::string& user_config,
                              const std::string& calibration) {
  ConfigLoader loader;
  if (camera_yaml) loader.applyFile(*camera_yaml);
  if (!user_config.empty()) loader.applyFile(user_config);
  if (!calibration.empty()) {
    // The calibration's intrinsics, size and distortion, as a last layer over the camera section.
    const Calibration c = readCalibration(calibration);
    char text[1024];
    std::snprintf(text, sizeof(text),
                  "camera:\n  image_width: %d\n  image_height: %d\n  fx: %.17g\n  fy: %.17g\n  cx: %.17g\n  cy: %.17g\n"
                  "  distortion: [%.17g, %.17g, %.17g, %.17g, %.17g]\n  distortion_model: %s\n",
                  c.image_width, c.image_height, c.fx, c.fy, c.cx, c.cy, c.distortion[0], c.distortion[1], c.distortion[2],
                  c.distortion[3], c.distortion[4], c.distortion_model.c_str());
    loader.applyText(text, calibration + " (" + c.format + " calibration)");
  }
  return loader.finish();
}

std::string configToYaml(const RunSettings& settings, const std::vector<std::string>& only_sections) {
  YAML::Emitter out;
  out.SetNullFormat(YAML::LowerNull);  // `null`, as docs/conventions.md writes it
  out << YAML::BeginMap;
  FieldWriter writer(out, only_sections);
  visitSettingsFields(settings, writer);
  writer.close();
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace groundslam
