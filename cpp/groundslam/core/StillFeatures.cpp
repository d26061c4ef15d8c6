#include "groundslam/core/StillFeatures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "groundslam/core/Hamming.hpp"

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

std::vector<Match> findStillFeatures(const GroundFeatures& query, const GroundFeatures& train, double radius, int max_hamming) {
  std::vector<Match> still;
  if (!query.hasRays() || !train.hasRays() || !(radius > 0.0) || train.size() == 0) return still;
  // Train features bucketed by image cells of the radius, sorted by cell: each query looks in its 3 x 3 cells.
  const auto cell = [&](double v) { return static_cast<std::int64_t>(std::floor(v / radius)); };
  const auto key = [](std::int64_t cx, std::int64_t cy) {
    return (static_cast<std::uint64_t>(cx) << 32) ^ static_cast<std::uint32_t>(cy);
  };
  std::vector<std::pair<std::uint64_t, int>> buckets;
  buckets.reserve(train.size());
  for (size_t t = 0; t < train.size(); ++t) buckets.emplace_back(key(cell(train.rays[t].x()), cell(train.rays[t].y())), static_cast<int>(t));
  std::sort(buckets.begin(), buckets.end());
  const double r2 = radius * radius;
  for (size_t q = 0; q < query.size(); ++q) {
    const Eigen::Vector2d& a = query.rays[q];
    const std::uint8_t* da = query.descriptors.ptr<std::uint8_t>(static_cast<int>(q));
    int best = -1, best_distance = max_hamming + 1;
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        const std::uint64_t k = key(cell(a.x()) + dx, cell(a.y()) + dy);
        auto it = std::lower_bound(buckets.begin(), buckets.end(), std::make_pair(k, -1));
        for (; it != buckets.end() && it->first == k; ++it) {
          const size_t t = static_cast<size_t>(it->second);
          if ((train.rays[t] - a).squaredNorm() > r2) continue;
          const int d = hammingDistance256(da, train.descriptors.ptr<std::uint8_t>(it->second));
          if (d < best_distance) best = it->second, best_distance = d;
        }
      }
    }
    if (best >= 0) still.push_back({static_cast<int>(q), best, best_distance});
  }
  return still;
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
  std::vector<bool> keep(features.size());
  for (size_t i = 0; i < features.size(); ++i) keep[i] = !isArtifact(features.rays[i]);
  return selectFeatures(features, keep);
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
