#pragma once
// The places loop closure can return to. Not every frame is kept: a frame whose footprint a kept place
// already covers (within `spacing`) adds nothing a loop closure needs, so memory grows with the ground
// covered, not with time, and a robot driving over the same floor for hours keeps a bounded map. Places sit
// in a spatial grid (candidates near an estimate cost the same however large the map is) and in the
// bag-of-words database (the paper's global search).

#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "groundslam/bow/BowDatabase.hpp"
#include "groundslam/bow/Vocabulary.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Pose2.hpp"

namespace groundslam {

/// A kept frame: its ground features (points as float: 8 bytes instead of 16, still 1e-7 of a footprint)
/// and bag-of-words vector.
struct Place {
  int frame = 0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  ///< the frame's estimated position, kept current by moveFrom
  std::vector<Eigen::Vector2f> points;
  std::vector<Eigen::Vector2f> rays;  ///< the points' normalised image rays, when the frame's features had them
  cv::Mat descriptors;
  BowVector bow;

  /// The features as the matcher and the fit take them.
  GroundFeatures features() const;
  /// Bytes this place holds (points, descriptors, BoW vector and its database postings).
  size_t bytes() const;
};

class PlaceMap {
 public:
  /// True when a place lies within `spacing_m` of `position`.
  bool covers(const Eigen::Vector2d& position, double spacing_m) const;
  /// Keeps `frame`, estimated at `position`, as a place.
  void add(int frame, const Eigen::Vector2d& position, const GroundFeatures& features, BowVector bow);

  /// The places whose position lies within `radius_m` of `where`, nearest first. Cost grows with the places
  /// in that disc, not with the map.
  std::vector<const Place*> near(const Eigen::Vector2d& where, double radius_m) const;
  /// The best `max_results` places by bag-of-words score over the whole map, best first.
  std::vector<BowMatch> query(const BowVector& bow, int max_results) const { return database_.query(bow, max_results); }
  /// The place kept for `frame`, or null.
  const Place* find(int frame) const;

  /// Moves the places of frames from `first_moved` on to `position_of(frame)` (after an optimisation moved
  /// their estimates) and re-files them: cost grows with those places only.
  void moveFrom(int first_moved, const std::function<Eigen::Vector2d(int frame)>& position_of);
  int size() const { return static_cast<int>(places_.size()); }
  size_t bytes() const { return bytes_; }

 private:
  using CellKey = std::uint64_t;
  CellKey cellOf(const Eigen::Vector2d& position) const;
  /// Calls f(place index) for every place filed in a cell within `radius_m` of `where`.
  template <class F>
  void forEachFiledNear(const Eigen::Vector2d& where, double radius_m, F&& f) const;

  std::vector<Place> places_;
  std::unordered_map<int, int> index_of_frame_;
  std::unordered_map<CellKey, std::vector<int>> grid_;  ///< cell -> places filed there
  std::vector<CellKey> filed_in_;                       ///< place -> its cell
  BowDatabase database_;
  size_t bytes_ = 0;
};

}  // namespace groundslam
