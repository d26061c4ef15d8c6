#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "groundslam/pipeline/Config.hpp"
#include "groundslam/pipeline/FramePreparer.hpp"

namespace groundslam {
namespace {

// Whether an enum field holds one of its declared values (a value cast from an integer in code may not); a
// switch without default, so that a new value the check does not know is a compiler warning.
bool declared(RobustLoss v) {
  switch (v) {
    case RobustLoss::huber:
    case RobustLoss::cauchy:
    case RobustLoss::geman_mcclure: return true;
  }
  return false;
}
bool declared(MatcherMethod v) {
  switch (v) {
    case MatcherMethod::brute_force:
    case MatcherMethod::lsh: return true;
  }
  return false;
}
bool declared(OrbScore v) {
  switch (v) {
    case OrbScore::harris:
    case OrbScore::fast: return true;
  }
  return false;
}
bool declared(DistortionModel v) {
  switch (v) {
    case DistortionModel::radtan:
    case DistortionModel::equidistant: return true;
  }
  return false;
}

/// The first field outside its allowed values, in the order of visitConfigFields.
class RangeChecker {
 public:
  template <class T, class Constraint>
  void operator()(const char* section, const char* key, const T& field, const Constraint& constraint) {
    if (!problem) check(std::string(section) + "." + key, field, constraint);
  }

  std::optional<ConfigProblem> problem;

 private:
  void check(const std::string& name, double value, const Range& range) {
    if (const auto message = rangeProblem(value, range)) problem = ConfigProblem{name, *message};
  }
  void check(const std::string& name, int value, const Range& range) { check(name, static_cast<double>(value), range); }
  void check(const std::string&, bool, const Range&) {}
  template <class Enum>
  void check(const std::string& name, Enum value, const OneOfNames&) {
    if (!declared(value)) problem = ConfigProblem{name, "value " + std::to_string(static_cast<int>(value)) + " is not one of the enum's values"};
  }
  template <size_t N>
  void check(const std::string& name, const std::array<double, N>& values, const Range& range) {
    for (double v : values) {
      if (!problem) check(name, v, range);
    }
  }
  template <class T>
  void check(const std::string& name, const std::optional<T>& value, const Range& range) {
    if (value) check(name, *value, range);
  }
};

/// T_robot_camera must be a rigid transform (a rotation and a translation) of a camera above the ground
/// whose whole image sees the ground.
std::optional<ConfigProblem> mountProblem(const CameraConfig& camera) {
  const std::string key = camera.T_robot_camera ? "camera.T_robot_camera" : "camera.mounting_height_m";
  if (camera.T_robot_camera) {
    const Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T(camera.T_robot_camera->data());
    const Eigen::Matrix3d R = T.block<3, 3>(0, 0);
    if (!T.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9) || (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-4 ||
        R.determinant() < 0.0) {
      return ConfigProblem{key, "not a rigid transform (rotation rows orthonormal, det +1, last row 0 0 0 1)"};
    }
    if (!(T(2, 3) > 0.0)) return ConfigProblem{key, "the camera is not above the ground (z = " + std::to_string(T(2, 3)) + " m)"};
  }
  if (cameraModelFrom(camera).groundFootprint().empty()) {
    return ConfigProblem{key, "part of the image does not look at the ground; groundslam needs a camera facing the floor"};
  }
  return std::nullopt;
}

/// OpenCV's ORB shrinks the image scale_factor^(num_levels-1) times at its top level; below a pixel it fails.
std::optional<ConfigProblem> pyramidProblem(const Config& config) {
  const OrbSettings& f = config.features;
  const int reduction = extractionReduction(config.camera.image_width, f.max_extraction_width);
  const double smallest = std::min(config.camera.image_width / reduction, config.camera.image_height / reduction) /
                          std::pow(f.scale_factor, f.num_levels - 1);
  if (smallest >= 1.0) return std::nullopt;
  std::ostringstream msg;
  msg << f.num_levels << " levels with scale_factor " << f.scale_factor << " shrink the " << config.camera.image_width / reduction
      << "x" << config.camera.image_height / reduction << " image ORB sees below one pixel at the top level; use fewer levels or a smaller factor";
  return ConfigProblem{"features.num_levels", msg.str()};
}

/// The search of a bridging frame tries a turn every bridge_search_turn_deg round the circle: a step under a degree
/// would try thousands per frame.
std::optional<ConfigProblem> searchProblem(const OdometryChecks& checks) {
  const double step = checks.bridge_search_turn_deg;
  if (step == 0.0 || step >= 1.0) return std::nullopt;
  return ConfigProblem{"odometry.bridge_search_turn_deg", "value " + std::to_string(step) + " is below 1 degree; use 0 (off) or 1 to 30"};
}

/// The heading images are off at 0; otherwise as wide as the alignment's own images must be at least.
std::optional<ConfigProblem> headingImageProblem(const OutdoorConfig& outdoor) {
  const int width = outdoor.heading_image_width_px;
  if (width == 0 || width >= 16) return std::nullopt;
  return ConfigProblem{"outdoor.heading_image_width_px", "value " + std::to_string(width) + " is below 16 pixels; use 0 (off) or 16 and more"};
}

}  // namespace

std::optional<std::string> rangeProblem(double value, const Range& range) {
  if (!std::isfinite(value)) return "value " + std::to_string(value) + " is not a finite number";
  const bool below = range.min_exclusive ? value <= range.min : value < range.min;
  if (!below && value <= range.max) return std::nullopt;
  std::ostringstream msg;
  msg << std::setprecision(12) << "value " << value << " out of range " << (range.min_exclusive ? "(" : "[") << range.min << ", "
      << range.max << "]";
  return msg.str();
}

std::optional<ConfigProblem> findConfigProblem(const Config& config) {
  RangeChecker ranges;
  visitConfigFields(config, ranges);
  if (ranges.problem) return ranges.problem;
  if (auto problem = mountProblem(config.camera)) return problem;
  if (auto problem = searchProblem(config.odometry_checks)) return problem;
  if (auto problem = headingImageProblem(config.outdoor)) return problem;
  return pyramidProblem(config);
}

void validateConfig(const Config& config) {
  if (const auto problem = findConfigProblem(config)) throw std::invalid_argument(problem->key + ": " + problem->message);
}

}  // namespace groundslam
