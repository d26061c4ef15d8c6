#include "groundslam/core/StillFeatures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

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
  // Train features in a grid over their image extent (cells of a few radii, linked lists): each query looks
  // in its 3 x 3 cells.
  Eigen::Vector2d lo = train.rays.front(), hi = lo;
  for (const Eigen::Vector2d& r : train.rays) lo = lo.cwiseMin(r), hi = hi.cwiseMax(r);
  double cell = 4.0 * radius;
  const double extent = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  if (extent / cell > 2000.0) cell = extent / 2000.0;  // a bounded grid whatever the rays
  const int nx = static_cast<int>((hi.x() - lo.x()) / cell) + 1, ny = static_cast<int>((hi.y() - lo.y()) / cell) + 1;
  std::vector<int> head(static_cast<size_t>(nx) * static_cast<size_t>(ny), -1), next(train.size(), -1);
  const auto cellOf = [&](const Eigen::Vector2d& r, int& cx, int& cy) {
    cx = static_cast<int>(std::floor((r.x() - lo.x()) / cell));
    cy = static_cast<int>(std::floor((r.y() - lo.y()) / cell));
  };
  for (size_t t = 0; t < train.size(); ++t) {
    int cx = 0, cy = 0;
    cellOf(train.rays[t], cx, cy);
    const size_t c = static_cast<size_t>(cy) * static_cast<size_t>(nx) + static_cast<size_t>(cx);
    next[t] = head[c];
    head[c] = static_cast<int>(t);
  }
  const double r2 = radius * radius;
  for (size_t q = 0; q < query.size(); ++q) {
    const Eigen::Vector2d& a = query.rays[q];
    int qx = 0, qy = 0;
    cellOf(a, qx, qy);
    const std::uint8_t* da = query.descriptors.ptr<std::uint8_t>(static_cast<int>(q));
    int best = -1, best_distance = max_hamming + 1;
    for (int y = std::max(0, qy - 1); y <= std::min(ny - 1, qy + 1); ++y) {
      for (int x = std::max(0, qx - 1); x <= std::min(nx - 1, qx + 1); ++x) {
        for (int t = head[static_cast<size_t>(y) * static_cast<size_t>(nx) + static_cast<size_t>(x)]; t >= 0; t = next[static_cast<size_t>(t)]) {
          if ((train.rays[static_cast<size_t>(t)] - a).squaredNorm() > r2) continue;
          const int d = hammingDistance256(da, train.descriptors.ptr<std::uint8_t>(t));
          if (d < best_distance || (d == best_distance && t < best)) best = t, best_distance = d;  // ties: the first feature
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
