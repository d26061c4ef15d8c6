#include "groundslam/sim/Paths.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

#include <opencv2/core.hpp>

namespace groundslam::sim {
namespace {

/// Moves a pose along an arc of length s and curvature kappa (exact for constant curvature).
Pose2 driveArc(const Pose2& pose, double s, double kappa) {
  if (std::abs(kappa) < 1e-12) {
    return Pose2(pose.x + s * std::cos(pose.theta), pose.y + s * std::sin(pose.theta), pose.theta);
  }
  const double dtheta = kappa * s;
  return Pose2(pose.x + (std::sin(pose.theta + dtheta) - std::sin(pose.theta)) / kappa,
               pose.y + (std::cos(pose.theta) - std::cos(pose.theta + dtheta)) / kappa, pose.theta + dtheta);
}

/// Integrates kappa(s) along the path in fine sub-steps; one pose per frame.
std::vector<Pose2> integrate(const PathSettings& settings, const Pose2& start,
                             const std::function<double(double)>& curvature_at) {
  constexpr int kSubsteps = 16;
  std::vector<Pose2> poses{start};
  Pose2 pose = start;
  const double ds = settings.step_m / kSubsteps;
  double s = 0.0;
  for (int frame = 1; frame < settings.frames; ++frame) {
    for (int k = 0; k < kSubsteps; ++k, s += ds) pose = driveArc(pose, ds, curvature_at(s + 0.5 * ds));
    poses.push_back(pose);
  }
  return poses;
}

std::vector<Pose2> loop(const PathSettings& settings) {
  const double length = settings.step_m * (settings.frames - 1);
  const double lap_length = length / std::max(1, settings.laps);
  const double radius = lap_length / (2.0 * M_PI);
  // The radius breathes by 4% at an incommensurate period so laps do not retrace each other exactly.
  auto curvature = [=](double s) { return 1.0 / (radius * (1.0 + 0.04 * std::sin(2.0 * M_PI * s / (1.37 * lap_length)))); };
  return integrate(settings, Pose2(0.0, -radius, 0.0), curvature);
}

std::vector<Pose2> lawnmower(const PathSettings& settings) {
  const double lane = settings.lane_length_m, turn_radius = 0.5 * settings.lane_spacing_m;
  const double turn = M_PI * turn_radius, period = lane + turn;
  auto curvature = [=](double s) {
    const double within = std::fmod(s, period);
    if (within < lane) return 0.0;
    const long index = static_cast<long>(s / period);
    return (index % 2 == 0 ? 1.0 : -1.0) / turn_radius;  // alternate left and right U-turns
  };
  return integrate(settings, Pose2(-0.5 * lane, 0.0, 0.0), curvature);
}

std::vector<Pose2> randomWalk(const PathSettings& settings) {
  cv::RNG rng(settings.seed);
  std::vector<Pose2> poses{Pose2()};
  const double max_kappa = settings.max_turn_rad / settings.step_m;
  double kappa = 0.0;
  for (int frame = 1; frame < settings.frames; ++frame) {
    const Pose2& pose = poses.back();
    // Smooth random steering (a first-order filter of white noise), pulled home near the border.
    kappa = 0.9 * kappa + 0.35 * max_kappa * rng.gaussian(1.0);
    const double half = 0.5 * settings.area_m, distance = std::hypot(pose.x, pose.y);
    if (distance > 0.6 * half) {
      const double home = std::atan2(-pose.y, -pose.x);
      kappa += 0.5 * max_kappa * wrapAngle(home - pose.theta) * std::min(1.0, (distance - 0.6 * half) / (0.4 * half));
    }
    kappa = std::clamp(kappa, -max_kappa, max_kappa);
    poses.push_back(driveArc(pose, settings.step_m, kappa));
  }
  return poses;
}

}  // namespace

const std::vector<std::string>& pathKindNames() {
  static const std::vector<std::string> names = {"loop", "lawnmower", "random_walk"};
  return names;
}

bool parsePathKind(const std::string& name, PathKind& kind) {
  const auto& names = pathKindNames();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return false;
  kind = static_cast<PathKind>(it - names.begin());
  return true;
}

std::string pathKindName(PathKind kind) { return pathKindNames()[static_cast<size_t>(kind)]; }

std::vector<Pose2> generatePath(const PathSettings& settings) {
  switch (settings.kind) {
    case PathKind::loop: return loop(settings);
    case PathKind::lawnmower: return lawnmower(settings);
    case PathKind::random_walk: return randomWalk(settings);
  }
  return {};
}

}  // namespace groundslam::sim
