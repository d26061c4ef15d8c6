#pragma once
// The map global localization searches: every ground feature stored once with its descriptor, octave and
// pose on the ground, and an inverted index from visual words to features. Features are kept relative to
// the keyframe (anchor) that saw them, so an optimisation that moves keyframes moves their features too.
// Features of overlapping keyframes are stored once: a feature is dropped when the map already holds one
// within `dedup_m` on the ground with a close descriptor.

#include <array>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "groundslam/bow/Vocabulary.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Pose2.hpp"

namespace groundslam {

/// One map feature: 52 bytes in memory (49 of data), 49 in a map file.
struct MapFeature {
  Descriptor descriptor{};       ///< ORB, 256 bits
  Eigen::Vector2f point;         ///< on the ground, in its anchor's robot frame, metres
  float angle_rad = 0.0f;        ///< ORB orientation on the ground, anchor frame
  std::uint32_t anchor = 0;      ///< index of the keyframe that saw it
  std::uint8_t octave = 0;       ///< ORB pyramid level
};

/// A keyframe of the map: the frame it came from, its pose and the session segment it belongs to.
struct MapAnchor {
  int frame = 0;           ///< frame index in the run that added it
  Pose2 T_map_anchor;      ///< current estimate
  int segment = 0;         ///< anchors of one segment share a frame; a new one starts after tracking is lost
};

struct FeatureMapSettings {
  double dedup_m = 0.002;    ///< (at most 0.01) a feature this close to a map feature with a close descriptor is not stored again
  int dedup_hamming = 50;    ///< "close descriptor", bits
};

class FeatureMap {
 public:
  FeatureMap(std::shared_ptr<const Vocabulary> vocabulary, const FeatureMapSettings& settings = {});

  /// Adds a keyframe at `T_map_anchor` with the features it saw that the map lacks (they need orientations);
  /// returns the anchor index.
  int addAnchor(int frame, const Pose2& T_map_anchor, int segment, const GroundFeatures& features);
  /// Adds a feature as stored (a map file), without the dedup check; the anchor must exist.
  void addStoredFeature(const MapFeature& feature);
  int addStoredAnchor(const MapAnchor& anchor);
  /// After an optimisation: the anchor's new pose (its features move with it).
  void moveAnchor(int anchor, const Pose2& T_map_anchor) { anchors_[static_cast<size_t>(anchor)].T_map_anchor = T_map_anchor; }
  /// Anchors from now on belong to `to` instead of `from` (a segment joined to the map).
  void mergeSegment(int from, int to);

  const std::vector<MapAnchor>& anchors() const { return anchors_; }
  const std::vector<MapFeature>& features() const { return features_; }
  const Vocabulary& vocabulary() const { return *vocabulary_; }
  /// Features with a visual word, for voting.
  const std::vector<std::uint32_t>& postings(int word) const;
  /// Map-frame position of a feature (its anchor's current pose applied).
  Eigen::Vector2d positionOf(const MapFeature& f) const;
  double angleOf(const MapFeature& f) const;
  const std::vector<std::uint32_t>& featuresOf(int anchor) const { return features_of_anchor_[static_cast<size_t>(anchor)]; }
  /// The features an anchor holds, in its robot frame, as a query for localization (those the map already had
  /// when it was added are not among them).
  GroundFeatures featuresInAnchorFrame(int anchor) const;
  /// Anchors whose position lies within `radius_m` of `where`.
  std::vector<int> anchorsNear(const Eigen::Vector2d& where, double radius_m) const;
  /// Bytes the map holds (features, postings, keyframe lists, dedup grid, keyframes), for the memory budget.
  size_t bytes() const;

 private:
  using CellKey = std::uint64_t;
  /// A feature of the segment's anchors lies this close with a close descriptor.
  bool alreadyMapped(const Eigen::Vector2d& position, const std::uint8_t* descriptor, int segment) const;
  void index(std::uint32_t feature_index, const Eigen::Vector2d& position);

  std::shared_ptr<const Vocabulary> vocabulary_;
  FeatureMapSettings settings_;
  std::vector<MapAnchor> anchors_;
  std::vector<MapFeature> features_;
  std::vector<std::vector<std::uint32_t>> postings_;               ///< word -> features
  std::vector<std::vector<std::uint32_t>> features_of_anchor_;     ///< anchor -> its features
  std::unordered_map<CellKey, std::vector<std::uint32_t>> dedup_grid_;  ///< positions when stored (for dedup only)
};

}  // namespace groundslam
