#include "groundslam/core/StillFeatures.hpp"

#include <algorithm>

namespace groundslam {

StillSplit splitStillMatches(const std::vector<Match>& matches, const GroundFeatures& query, const GroundFeatures& train,
                             double radius) {
  StillSplit split;
  if (!query.hasRays() || !train.hasRays()) {
    split.moving = matches;
    return split;
  }
  const double r2 = radius * radius;
  for (const Match& m : matches) {
    const Eigen::Vector2d& a = query.rays[static_cast<size_t>(m.query)];
    const Eigen::Vector2d& b = train.rays[static_cast<size_t>(m.train)];
    ((a - b).squaredNorm() <= r2 ? split.still : split.moving).push_back(m);
  }
  return split;
}

ArtifactMask::ArtifactMask(const CameraIntrinsics& intrinsics, const ArtifactMaskSettings& settings)
    : intrinsics_(intrinsics),
      settings_(settings),
      still_(static_cast<size_t>(std::max(1, settings.cells_x * settings.cells_y)), 0.0),
      moving_(still_.size(), 0.0) {}

int ArtifactMask::cellOf(const Eigen::Vector2d& ray) const {
  // The pinhole pixel of the ray: close enough to the distorted one for a cell of 16 pixels.
  const double u = intrinsics_.fx * ray.x() + intrinsics_.cx, v = intrinsics_.fy * ray.y() + intrinsics_.cy;
  const int cx = std::clamp(static_cast<int>(u / std::max(1, intrinsics_.width) * settings_.cells_x), 0, settings_.cells_x - 1);
  const int cy = std::clamp(static_cast<int>(v / std::max(1, intrinsics_.height) * settings_.cells_y), 0, settings_.cells_y - 1);
  return cy * settings_.cells_x + cx;
}

void ArtifactMask::fade() {
  for (size_t i = 0; i < still_.size(); ++i) {
    still_[i] *= settings_.fade;
    moving_[i] *= settings_.fade;
  }
}

void ArtifactMask::observe(const GroundFeatures& current, const std::vector<Match>& still, const std::vector<Match>& moving) {
  fade();
  if (!current.hasRays()) return;
  for (const Match& m : still) still_[static_cast<size_t>(cellOf(current.rays[static_cast<size_t>(m.query)]))] += 1.0;
  for (const Match& m : moving) moving_[static_cast<size_t>(cellOf(current.rays[static_cast<size_t>(m.query)]))] += 1.0;
}

bool ArtifactMask::isArtifact(const Eigen::Vector2d& ray) const {
  const size_t cell = static_cast<size_t>(cellOf(ray));
  return still_[cell] >= settings_.min_evidence && still_[cell] > moving_[cell];
}

GroundFeatures ArtifactMask::withoutArtifacts(const GroundFeatures& features) const {
  if (!features.hasRays() || artifactCells() == 0) return features;
  GroundFeatures kept;
  for (size_t i = 0; i < features.size(); ++i) {
    if (isArtifact(features.rays[i])) continue;
    kept.points.push_back(features.points[i]);
    kept.descriptors.push_back(features.descriptors.row(static_cast<int>(i)));
    kept.rays.push_back(features.rays[i]);
    if (features.hasOrientations()) {
      kept.angles_rad.push_back(features.angles_rad[i]);
      kept.octaves.push_back(features.octaves[i]);
    }
  }
  return kept;
}

std::vector<Match> ArtifactMask::withoutArtifacts(const std::vector<Match>& matches, const GroundFeatures& query) const {
  if (!query.hasRays()) return matches;
  std::vector<Match> kept;
  for (const Match& m : matches) {
    if (!isArtifact(query.rays[static_cast<size_t>(m.query)])) kept.push_back(m);
  }
  return kept;
}

int ArtifactMask::artifactCells() const {
  int count = 0;
  for (size_t i = 0; i < still_.size(); ++i) count += still_[i] >= settings_.min_evidence && still_[i] > moving_[i] ? 1 : 0;
  return count;
}

}  // namespace groundslam
