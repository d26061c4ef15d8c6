#include "groundslam/localization/FeatureMap.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "groundslam/core/Hamming.hpp"

namespace groundslam {
namespace {

constexpr double kDedupCellM = 0.01;  // the dedup grid's cell; a cell's neighbours cover dedup_m up to a cell

std::uint64_t cellKey(std::int64_t cx, std::int64_t cy) {
  return (static_cast<std::uint64_t>(cx) << 32) ^ (static_cast<std::uint64_t>(cy) & 0xffffffffu);
}

}  // namespace

FeatureMap::FeatureMap(std::shared_ptr<const Vocabulary> vocabulary, const FeatureMapSettings& settings)
    : vocabulary_(std::move(vocabulary)), settings_(settings), postings_(static_cast<size_t>(vocabulary_->wordCount())) {}

int FeatureMap::addStoredAnchor(const MapAnchor& anchor) {
  anchors_.push_back(anchor);
  features_of_anchor_.emplace_back();
  return static_cast<int>(anchors_.size()) - 1;
}

int FeatureMap::addAnchor(int frame, const Pose2& T_map_anchor, int segment, const GroundFeatures& features) {
  const int anchor = addStoredAnchor({frame, T_map_anchor, segment});
  if (!features.hasOrientations()) return anchor;
  const Eigen::Matrix2d R = T_map_anchor.rotation();  // once, not per feature
  for (size_t i = 0; i < features.size(); ++i) {
    const std::uint8_t* descriptor = features.descriptors.ptr<std::uint8_t>(static_cast<int>(i));
    const Eigen::Vector2d position = R * features.points[i] + T_map_anchor.translation();
    if (alreadyMapped(position, descriptor, segment)) continue;
    MapFeature f;
    std::memcpy(f.descriptor.data(), descriptor, f.descriptor.size());
    f.point = features.points[i].cast<float>();
    f.angle_rad = features.angles_rad[i];
    f.anchor = static_cast<std::uint32_t>(anchor);
    f.octave = features.octaves[i];
    addStoredFeature(f);
  }
  return anchor;
}

void FeatureMap::addStoredFeature(const MapFeature& feature) {
  const auto index = static_cast<std::uint32_t>(features_.size());
  features_.push_back(feature);
  this->index(index, positionOf(feature));
  const int word = vocabulary_->wordOf(feature.descriptor.data());
  if (word >= 0) postings_[static_cast<size_t>(word)].push_back(index);
  features_of_anchor_[feature.anchor].push_back(index);
}

void FeatureMap::index(std::uint32_t feature_index, const Eigen::Vector2d& position) {
  const double cell = kDedupCellM;
  dedup_grid_[cellKey(static_cast<std::int64_t>(std::floor(position.x() / cell)),
                      static_cast<std::int64_t>(std::floor(position.y() / cell)))]
      .push_back(feature_index);
}

bool FeatureMap::alreadyMapped(const Eigen::Vector2d& position, const std::uint8_t* descriptor, int segment) const {
  if (settings_.dedup_m <= 0.0) return false;
  const double cell = kDedupCellM;
  const auto cx = static_cast<std::int64_t>(std::floor(position.x() / cell));
  const auto cy = static_cast<std::int64_t>(std::floor(position.y() / cell));
  for (std::int64_t dx = -1; dx <= 1; ++dx) {
    for (std::int64_t dy = -1; dy <= 1; ++dy) {
      const auto it = dedup_grid_.find(cellKey(cx + dx, cy + dy));
      if (it == dedup_grid_.end()) continue;
      for (const std::uint32_t i : it->second) {
        // The descriptor first: a few nanoseconds, and it rules out almost every neighbour before the position's
        // sine and cosine are needed.
        if (hammingDistance256(descriptor, features_[i].descriptor.data()) > settings_.dedup_hamming) continue;
        // Another segment's positions are relative to another guess: the same place on the ground is elsewhere.
        if (anchors_[features_[i].anchor].segment != segment) continue;
        if ((positionOf(features_[i]) - position).squaredNorm() <= settings_.dedup_m * settings_.dedup_m) return true;
      }
    }
  }
  return false;
}

void FeatureMap::mergeSegment(int from, int to) {
  for (MapAnchor& a : anchors_) {
    if (a.segment == from) a.segment = to;
  }
}

const std::vector<std::uint32_t>& FeatureMap::postings(int word) const {
  static const std::vector<std::uint32_t> none;
  if (word < 0 || static_cast<size_t>(word) >= postings_.size()) return none;
  return postings_[static_cast<size_t>(word)];
}

Eigen::Vector2d FeatureMap::positionOf(const MapFeature& f) const {
  return anchors_[f.anchor].T_map_anchor * f.point.cast<double>();
}

double FeatureMap::angleOf(const MapFeature& f) const { return wrapAngle(anchors_[f.anchor].T_map_anchor.theta + f.angle_rad); }

std::vector<int> FeatureMap::anchorsNear(const Eigen::Vector2d& where, double radius_m) const {
  std::vector<int> near;
  for (size_t i = 0; i < anchors_.size(); ++i) {
    if ((anchors_[i].T_map_anchor.translation() - where).norm() <= radius_m) near.push_back(static_cast<int>(i));
  }
  return near;
}

size_t FeatureMap::bytes() const {
  size_t grid = 0;
  for (const auto& [cell, members] : dedup_grid_) grid += members.capacity() * sizeof(std::uint32_t) + 48;  // + node
  // Per feature: itself, its posting, its entry in its anchor's list and in the dedup grid.
  return features_.size() * (sizeof(MapFeature) + 2 * sizeof(std::uint32_t)) + anchors_.size() * sizeof(MapAnchor) + grid;
}

GroundFeatures FeatureMap::featuresInAnchorFrame(int anchor) const {
  const std::vector<std::uint32_t>& indices = featuresOf(anchor);
  GroundFeatures features;
  features.descriptors.create(static_cast<int>(indices.size()), 32, CV_8U);
  for (size_t i = 0; i < indices.size(); ++i) {
    const MapFeature& f = features_[indices[i]];
    features.points.push_back(f.point.cast<double>());
    features.angles_rad.push_back(f.angle_rad);
    features.octaves.push_back(f.octave);
    std::copy(f.descriptor.begin(), f.descriptor.end(), features.descriptors.ptr<std::uint8_t>(static_cast<int>(i)));
  }
  return features;
}

}  // namespace groundslam
