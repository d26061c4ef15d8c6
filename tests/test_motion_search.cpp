// Searching a motion among the ones the robot can have made (core/MotionSearch): a quarter turn on the spot over
// a floor that shares few features between the two images is found; what is not there is not invented.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "groundslam/core/MotionSearch.hpp"

namespace groundslam {
namespace {

constexpr double kDeg = M_PI / 180.0;

cv::Mat randomDescriptor(std::mt19937& rng) {
  cv::Mat d(1, 32, CV_8U);
  for (int b = 0; b < 32; ++b) d.at<std::uint8_t>(0, b) = static_cast<std::uint8_t>(rng() & 0xff);
  return d;
}

/// A descriptor like one of eight prototypes, 36 of its bits flipped: a floor whose unrelated features look alike
/// (two of them differ by about 65 bits, within the search's 80-bit bound).
cv::Mat lookAlikeDescriptor(std::mt19937& rng) {
  static const std::vector<cv::Mat> prototypes = [] {
    std::mt19937 r(99);
    std::vector<cv::Mat> p;
    for (int k = 0; k < 8; ++k) p.push_back(randomDescriptor(r));
    return p;
  }();
  cv::Mat d = prototypes[rng() % prototypes.size()].clone();
  for (int k = 0; k < 36; ++k) {
    const int bit = static_cast<int>(rng() % 256);
    d.at<std::uint8_t>(0, bit / 8) ^= static_cast<std::uint8_t>(1u << (bit % 8));
  }
  return d;
}

Eigen::Vector2d randomPoint(std::mt19937& rng) {
  std::uniform_real_distribution<double> x(-0.09, 0.09), y(-0.07, 0.07);  // a 320 x 240 image at 25 cm
  return {x(rng), y(rng)};
}

/// Two images' features: `shared` ground features seen by both (the query's at T_train_query^-1 of the train's,
/// 0.1 mm noise, 30 of 256 descriptor bits flipped), and the rest of each image unrelated (look-alikes when
/// `look_alike`: every window then holds pairs within the Hamming bound).
std::pair<GroundFeatures, GroundFeatures> twoImages(const Pose2& T_train_query, int shared, int total, std::uint32_t seed,
                                                    bool look_alike = true) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1e-4);
  GroundFeatures train, query;
  const Pose2 T_query_train = T_train_query.inverse();
  while (static_cast<int>(query.size()) < shared) {
    const Eigen::Vector2d p_train = randomPoint(rng);
    const Eigen::Vector2d p_query = T_query_train * p_train + Eigen::Vector2d(noise(rng), noise(rng));
    if (std::abs(p_query.x()) > 0.09 || std::abs(p_query.y()) > 0.07) continue;  // outside the second image
    const cv::Mat d = randomDescriptor(rng);
    cv::Mat flipped = d.clone();
    for (int k = 0; k < 30; ++k) {
      const int bit = static_cast<int>(rng() % 256);
      flipped.at<std::uint8_t>(0, bit / 8) ^= static_cast<std::uint8_t>(1u << (bit % 8));
    }
    train.points.push_back(p_train);
    train.descriptors.push_back(d);
    query.points.push_back(p_query);
    query.descriptors.push_back(flipped);
  }
  for (GroundFeatures* f : {&train, &query}) {
    while (static_cast<int>(f->size()) < total) {
      f->points.push_back(randomPoint(rng));
      f->descriptors.push_back(look_alike ? lookAlikeDescriptor(rng) : randomDescriptor(rng));
    }
  }
  return {train, query};
}

/// Nothing is believed among `hypotheses`; with rivals allowed a chance fit is returned, with a rival over half its
/// inliers: the rival test is what refuses it.
void expectOnlyChanceFits(const GroundFeatures& query, const GroundFeatures& train, const std::vector<Pose2>& hypotheses) {
  EXPECT_FALSE(searchMotion(query, train, hypotheses, MotionSearchSettings{}, FitSettings{}).has_value());
  MotionSearchSettings lenient;
  lenient.max_rival_share = 1.01;
  const auto chance = searchMotion(query, train, hypotheses, lenient, FitSettings{});
  ASSERT_TRUE(chance.has_value());
  EXPECT_GT(chance->rival_inliers, chance->fit.inliers / 2);
}

TEST(MotionSearch, AQuarterTurnOnTheSpotIsFoundAmongTheTurnsEveryFiveDegrees) {
  // The robot stepped 1.2 cm and turned 91.8 degrees; 30 of 800 features per image are ground both show. The
  // hypotheses 90 and 95 degrees put them within the window; the fit recovers the motion to keypoint noise.
  const Pose2 truth(0.0119, 0.0030, 91.8 * kDeg);
  const auto [train, query] = twoImages(truth, 30, 800, 7, false);
  const auto found = searchMotion(query, train, turnHypotheses(Pose2(0.01, 0.0, 0.0), 5.0 * kDeg), MotionSearchSettings{}, FitSettings{});
  ASSERT_TRUE(found.has_value());
  EXPECT_LT((found->fit.T_target_source.translation() - truth.translation()).norm(), 3e-4);
  EXPECT_LT(std::abs(wrapAngle(found->fit.T_target_source.theta - truth.theta)), 0.2 * kDeg);
  EXPECT_GE(found->fit.inliers, 27);
  EXPECT_LT(found->rival_inliers, found->fit.inliers / 2);
}

TEST(MotionSearch, NothingIsFoundWhereNoHypothesisIsNearTheMotion) {
  // The same pair, searched only among turns within 30 degrees of straight on: no window holds the shared
  // features. The look-alike pairs the windows hold do give fits, each near its own hypothesis and as strong as
  // its neighbours' (with rivals allowed, one is returned): none stands out, so none is believed.
  const auto [train, query] = twoImages(Pose2(0.0119, 0.0030, 91.8 * kDeg), 30, 800, 7);
  std::vector<Pose2> near_straight;
  for (int d = -30; d <= 30; d += 5) near_straight.emplace_back(0.01, 0.0, d * kDeg);
  expectOnlyChanceFits(query, train, near_straight);
}

TEST(MotionSearch, TwoImagesWithNoGroundInCommonGiveNoMotion) {
  // Only look-alikes (every window holds pairs within 80 bits): chance fits over the full circle of turns, none
  // standing out, so none is believed; with rivals allowed one is returned.
  const auto [train, query] = twoImages(Pose2(), 0, 800, 11);
  expectOnlyChanceFits(query, train, turnHypotheses(Pose2(0.01, 0.0, 0.0), 5.0 * kDeg));
}

TEST(MotionSearch, AMotionThatTwoDistinctHypothesesExplainAlikeIsRefused) {
  // Half the shared features moved one way, half another (a floor that repeats): two fits of about 15 inliers,
  // 90 degrees apart; neither has twice the other's.
  auto [train, query] = twoImages(Pose2(0.01, 0.0, 90.0 * kDeg), 16, 400, 3);
  const auto [train2, query2] = twoImages(Pose2(0.01, 0.0, 0.0), 16, 16, 5);
  for (size_t i = 0; i < train2.size(); ++i) {
    train.points.push_back(train2.points[i]);
    train.descriptors.push_back(train2.descriptors.row(static_cast<int>(i)));
    query.points.push_back(query2.points[i]);
    query.descriptors.push_back(query2.descriptors.row(static_cast<int>(i)));
  }
  const std::vector<Pose2> turns = turnHypotheses(Pose2(0.01, 0.0, 0.0), 5.0 * kDeg);
  EXPECT_FALSE(searchMotion(query, train, turns, MotionSearchSettings{}, FitSettings{}).has_value());
  MotionSearchSettings lenient;  // a rival as strong as the fit allowed: both are there
  lenient.max_rival_share = 1.01;
  const auto either = searchMotion(query, train, turns, lenient, FitSettings{});
  ASSERT_TRUE(either.has_value());
  EXPECT_GE(either->rival_inliers, 12);
}

TEST(MotionSearch, TurnHypothesesCoverTheCircleOnce) {
  const std::vector<Pose2> turns = turnHypotheses(Pose2(0.01, 0.002, 0.3), 5.0 * kDeg);
  ASSERT_EQ(turns.size(), 72u);
  EXPECT_NEAR(turns.front().theta, -175.0 * kDeg, 1e-9);
  EXPECT_NEAR(std::abs(turns.back().theta), 180.0 * kDeg, 1e-9);
  EXPECT_DOUBLE_EQ(turns[10].x, 0.01);
  EXPECT_DOUBLE_EQ(turns[10].y, 0.002);
  EXPECT_TRUE(turnHypotheses(Pose2(), 0.0).empty());
}

}  // namespace
}  // namespace groundslam
