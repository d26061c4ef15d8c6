#include "groundslam/pipeline/PlaceMap.hpp"

#include <algorithm>
#include <cmath>

namespace groundslam {
namespace {

constexpr double kCellSizeM = 0.25;

std::uint64_t cellKey(std::int64_t cx, std::int64_t cy) {
  return (static_cast<std::uint64_t>(cx) << 32) ^ (static_cast<std::uint64_t>(cy) & 0xffffffffu);
}

}  // namespace

GroundFeatures Place::features() const {
  GroundFeatures features;
  features.points.reserve(points.size());
  for (const Eigen::Vector2f& p : points) features.points.push_back(p.cast<double>());
  features.rays.reserve(rays.size());
  for (const Eigen::Vector2f& r : rays) features.rays.push_back(r.cast<double>());
  features.descriptors = descriptors;  // shares the data
  return features;
}

size_t Place::bytes() const {
  const size_t bow_bytes = bow.size() * sizeof(BowVector::value_type);
  return sizeof(Place) + (points.size() + rays.size()) * sizeof(Eigen::Vector2f) + descriptors.total() * descriptors.elemSize() +
         2 * bow_bytes;  // the vector and its postings in the database
}

PlaceMap::CellKey PlaceMap::cellOf(const Eigen::Vector2d& position) const {
  const auto cx = static_cast<std::int64_t>(std::floor(position.x() / kCellSizeM));
  const auto cy = static_cast<std::int64_t>(std::floor(position.y() / kCellSizeM));
  return cellKey(cx, cy);
}

template <class F>
void PlaceMap::forEachFiledNear(const Eigen::Vector2d& where, double radius_m, F&& f) const {
  const auto lo_x = static_cast<std::int64_t>(std::floor((where.x() - radius_m) / kCellSizeM));
  const auto hi_x = static_cast<std::int64_t>(std::floor((where.x() + radius_m) / kCellSizeM));
  const auto lo_y = static_cast<std::int64_t>(std::floor((where.y() - radius_m) / kCellSizeM));
  const auto hi_y = static_cast<std::int64_t>(std::floor((where.y() + radius_m) / kCellSizeM));
  for (std::int64_t cx = lo_x; cx <= hi_x; ++cx) {
    for (std::int64_t cy = lo_y; cy <= hi_y; ++cy) {
      const auto cell = grid_.find(cellKey(cx, cy));
      if (cell == grid_.end()) continue;
      for (const int place : cell->second) f(place);
    }
  }
}

bool PlaceMap::covers(const Eigen::Vector2d& position, double spacing_m) const {
  // Position alone: ORB is rotation invariant, and a footprint turned about its centre still shares most of
  // its ground with the unturned one.
  bool covered = false;
  forEachFiledNear(position, spacing_m, [&](int place) {
    if ((places_[static_cast<size_t>(place)].position - position).norm() < spacing_m) covered = true;
  });
  return covered;
}

void PlaceMap::add(int frame, const Eigen::Vector2d& position, const GroundFeatures& features, BowVector bow) {
  Place place;
  place.frame = frame;
  place.position = position;
  place.points.reserve(features.size());
  for (const Eigen::Vector2d& p : features.points) place.points.push_back(p.cast<float>());
  if (features.hasRays()) {
    place.rays.reserve(features.size());
    for (const Eigen::Vector2d& r : features.rays) place.rays.push_back(r.cast<float>());
  }
  place.descriptors = features.descriptors.clone();  // its own compact buffer, not a view into a larger one
  place.bow = std::move(bow);
  database_.add(frame, place.bow);
  bytes_ += place.bytes();
  const int index = static_cast<int>(places_.size());
  index_of_frame_[frame] = index;
  const CellKey cell = cellOf(position);
  grid_[cell].push_back(index);
  filed_in_.push_back(cell);
  places_.push_back(std::move(place));
}

std::vector<const Place*> PlaceMap::near(const Eigen::Vector2d& where, double radius_m) const {
  std::vector<std::pair<double, int>> found;  // (distance, place index): the earlier frame breaks ties
  std::vector<const Place*> places;
  forEachFiledNear(where, radius_m, [&](int index) {
    const Place& place = places_[static_cast<size_t>(index)];
    const double distance = (place.position - where).norm();
    if (distance <= radius_m) found.emplace_back(distance, index);
  });
  std::sort(found.begin(), found.end());
  places.reserve(found.size());
  for (const auto& [distance, index] : found) places.push_back(&places_[static_cast<size_t>(index)]);
  return places;
}

const Place* PlaceMap::find(int frame) const {
  const auto found = index_of_frame_.find(frame);
  return found == index_of_frame_.end() ? nullptr : &places_[static_cast<size_t>(found->second)];
}

void PlaceMap::moveFrom(int first_moved, const std::function<Eigen::Vector2d(int frame)>& position_of) {
  // Places are added in frame order: those of frames from first_moved on are a suffix.
  const auto first = std::partition_point(places_.begin(), places_.end(), [&](const Place& p) { return p.frame < first_moved; });
  for (auto place = first; place != places_.end(); ++place) {
    const auto index = static_cast<size_t>(place - places_.begin());
    place->position = position_of(place->frame);
    const CellKey now = cellOf(place->position);
    if (now == filed_in_[index]) continue;
    std::vector<int>& old_cell = grid_[filed_in_[index]];
    old_cell.erase(std::find(old_cell.begin(), old_cell.end(), static_cast<int>(index)));
    grid_[now].push_back(static_cast<int>(index));
    filed_in_[index] = now;
  }
}

}  // namespace groundslam
