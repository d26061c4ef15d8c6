#pragma once
// The names by which configuration files spell the values of the configuration's enums
// (odometry.loss: huber, ...). Only the readers and writers of files need them; the algorithm uses the enums.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/RigidFit.hpp"

namespace groundslam {

template <class Enum>
using NameTable = std::vector<std::pair<Enum, std::string>>;

/// Every value of the enum with its name, in declaration order (the argument only selects the table).
const NameTable<RobustLoss>& namesOf(RobustLoss);
const NameTable<MatcherMethod>& namesOf(MatcherMethod);
const NameTable<OrbScore>& namesOf(OrbScore);
const NameTable<DistortionModel>& namesOf(DistortionModel);

/// The name of `value`; "?" for a value the enum does not declare.
template <class Enum>
std::string nameOf(Enum value) {
  for (const auto& [v, name] : namesOf(value)) {
    if (v == value) return name;
  }
  return "?";
}

/// The value named `name`, or empty.
template <class Enum>
std::optional<Enum> valueNamed(const std::string& name) {
  for (const auto& [v, n] : namesOf(Enum{})) {
    if (n == name) return v;
  }
  return std::nullopt;
}

/// "a, b, c": the names an enum accepts, for error messages.
template <class Enum>
std::string allowedNames() {
  std::string names;
  for (const auto& [v, name] : namesOf(Enum{})) names += (names.empty() ? "" : ", ") + name;
  return names;
}

}  // namespace groundslam
