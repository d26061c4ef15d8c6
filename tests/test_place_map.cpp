// The loop closer's map of places: spacing, nearest-first search, the global query, and moving places.
#include <gtest/gtest.h>

#include "groundslam/pipeline/PlaceMap.hpp"

using namespace groundslam;

namespace {

GroundFeatures someFeatures(int frame) {
  GroundFeatures f;
  for (int i = 0; i < 8; ++i) f.points.emplace_back(0.01 * i + 1e-4 * frame, -0.02 * i);
  f.descriptors = cv::Mat(8, 32, CV_8U, cv::Scalar(frame % 256));
  return f;
}

/// Frames every centimetre along x (twice: frames 100..199 drive the same line again), offset by `shift_y`.
std::vector<Pose2> lineDrivenTwice(double shift_y) {
  std::vector<Pose2> poses;
  for (int i = 0; i < 200; ++i) poses.emplace_back(0.01 * (i % 100), shift_y, 0.1 * i);
  return poses;
}

/// Admits every frame that the map does not cover yet, as the loop closer does.
PlaceMap mapOf(const std::vector<Pose2>& estimates, double spacing_m) {
  PlaceMap map;
  for (int frame = 0; frame < static_cast<int>(estimates.size()); ++frame) {
    const Eigen::Vector2d position = estimates[size_t(frame)].translation();
    if (!map.covers(position, spacing_m)) map.add(frame, position, someFeatures(frame), {{frame, 1.0f}});
  }
  return map;
}

/// The frames of the places within `radius_m` of `where`, nearest first.
std::vector<int> framesNear(const PlaceMap& map, const Eigen::Vector2d& where, double radius_m) {
  std::vector<int> frames;
  for (const Place* place : map.near(where, radius_m)) frames.push_back(place->frame);
  return frames;
}

}  // namespace

TEST(PlaceMap, KeepsOnePlacePerSpacingAndNothingOnTheSecondPass) {
  const std::vector<Pose2> estimates = lineDrivenTwice(0.0);
  const PlaceMap map = mapOf(estimates, 0.025);
  // Frames 0, 3, 6, ..., 99 (3 cm apart, the first not within 2.5 cm of the last kept); the second pass
  // over the same line adds none.
  EXPECT_EQ(map.size(), 34);
  EXPECT_NE(map.find(99), nullptr);
  EXPECT_EQ(map.find(98), nullptr);
  EXPECT_EQ(map.find(150), nullptr);
  EXPECT_GT(map.bytes(), 34u * (8 * 8 + 8 * 32));
}

TEST(PlaceMap, FindsNearbyPlacesNearestFirst) {
  const std::vector<Pose2> estimates = lineDrivenTwice(0.0);
  const PlaceMap map = mapOf(estimates, 0.025);
  EXPECT_EQ(framesNear(map, {0.5, 0.0}, 0.045), (std::vector<int>{51, 48, 54}));
  EXPECT_EQ(framesNear(map, {0.5, 0.3}, 0.045), std::vector<int>{});
}

TEST(PlaceMap, KeepsFeaturesToFloatPrecisionAndAnswersTheGlobalQuery) {
  const std::vector<Pose2> estimates = lineDrivenTwice(0.0);
  const PlaceMap map = mapOf(estimates, 0.025);
  const GroundFeatures original = someFeatures(51);
  const GroundFeatures kept = map.find(51)->features();
  ASSERT_EQ(kept.size(), original.size());
  for (size_t i = 0; i < kept.size(); ++i) EXPECT_LT((kept.points[i] - original.points[i]).norm(), 1e-8);
  EXPECT_EQ(cv::norm(kept.descriptors, original.descriptors, cv::NORM_HAMMING), 0.0);
  const std::vector<BowMatch> best = map.query({{51, 1.0f}}, 3);
  ASSERT_EQ(best.size(), 1u);  // no other place shares word 51
  EXPECT_EQ(best[0].frame, 51);
  EXPECT_DOUBLE_EQ(best[0].score, 1.0);
}

TEST(PlaceMap, MovedPlacesAreFoundWhereTheOptimisedMapPutsThem) {
  std::vector<Pose2> estimates = lineDrivenTwice(0.0);
  PlaceMap map = mapOf(estimates, 0.025);
  estimates = lineDrivenTwice(1.0);  // a correction moved the whole map by a metre
  EXPECT_EQ(framesNear(map, {0.5, 1.0}, 0.045), std::vector<int>{});  // the places are still at y = 0
  map.moveFrom(50, [&](int frame) { return estimates[size_t(frame)].translation(); });  // a window from frame 50 on moved
  EXPECT_EQ(framesNear(map, {0.5, 1.0}, 0.045), (std::vector<int>{51, 54}));
  EXPECT_LT((map.find(51)->position - Eigen::Vector2d(0.51, 1.0)).norm(), 1e-12);
  EXPECT_LT((map.find(48)->position - Eigen::Vector2d(0.48, 0.0)).norm(), 1e-12);
  EXPECT_EQ(framesNear(map, {0.2, 1.0}, 0.045), std::vector<int>{});  // frame 21 was not moved
  map.moveFrom(0, [&](int frame) { return estimates[size_t(frame)].translation(); });  // the whole map moved
  EXPECT_EQ(framesNear(map, {0.5, 1.0}, 0.045), (std::vector<int>{51, 48, 54}));
  EXPECT_EQ(framesNear(map, {0.2, 1.0}, 0.045), (std::vector<int>{21, 18, 24}));
}
