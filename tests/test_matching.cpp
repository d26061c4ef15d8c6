#include <random>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/NearestDescriptors.hpp"
#include "groundslam/io/ConfigNames.hpp"

using namespace groundslam;

namespace {

cv::Mat randomDescriptors(int n, unsigned seed) {
  cv::Mat d(n, 32, CV_8U);
  cv::RNG rng(seed);
  rng.fill(d, cv::RNG::UNIFORM, 0, 256);
  return d;
}

/// Flips `bits` random bits of a descriptor row.
cv::Mat flipBits(const cv::Mat& row, int bits, std::mt19937& rng) {
  cv::Mat out = row.clone();
  std::uniform_int_distribution<int> pick(0, 255);
  for (int b = 0; b < bits; ++b) {
    const int bit = pick(rng);
    out.at<unsigned char>(0, bit / 8) = static_cast<unsigned char>(out.at<unsigned char>(0, bit / 8) ^ (1 << (bit % 8)));
  }
  return out;
}

}  // namespace

TEST(Matching, RatioTestKeepsDistinctMatchesAndDropsAmbiguousOnes) {
  std::mt19937 rng(1);
  const cv::Mat train = randomDescriptors(200, 7);
  cv::Mat query;
  for (int i = 0; i < 100; ++i) query.push_back(flipBits(train.row(2 * i), 10, rng));  // close to train 2i
  // An ambiguous query: train rows 0 and 1 made equidistant twins of it.
  cv::Mat ambiguous_train = train.clone();
  flipBits(train.row(0), 0, rng).copyTo(ambiguous_train.row(1));
  for (const MatcherMethod method : {MatcherMethod::brute_force, MatcherMethod::lsh}) {
    DescriptorMatcher matcher({0.7, method});
    const auto matches = matcher.match(query, train);
    int correct = 0;
    for (const auto& m : matches) correct += (m.train == 2 * m.query) ? 1 : 0;
    EXPECT_GE(correct, method == MatcherMethod::lsh ? 90 : 100) << nameOf(method);
    EXPECT_EQ(correct, static_cast<int>(matches.size())) << nameOf(method);
    const auto twin_matches = DescriptorMatcher({0.7, MatcherMethod::brute_force}).match(query.row(0), ambiguous_train);
    EXPECT_TRUE(twin_matches.empty());
  }
}

TEST(Matching, BruteForceGivesExactlyOpenCvsKnnMatchesAfterTheRatioTest) {
  // Half the queries are noisy copies of train rows (true matches), half random (mostly rejected).
  std::mt19937 rng(3);
  cv::Mat train = randomDescriptors(400, 11);
  cv::Mat query = randomDescriptors(150, 12);
  for (int i = 0; i < 150; ++i) query.push_back(flipBits(train.row(i * 2), 5 + i % 40, rng));
  // A borderline pair: nearest at 63 bits, second at 90. 63 <= 0.7f * 90 holds in float (as OpenCV's
  // distances are), not in double.
  const auto withBits = [](int bits) {
    cv::Mat row(1, 32, CV_8U, cv::Scalar(0));
    for (int b = 0; b < bits; ++b) row.at<unsigned char>(0, b / 8) |= static_cast<unsigned char>(1 << (b % 8));
    return row;
  };
  query.push_back(withBits(0));
  withBits(63).copyTo(train.row(1));
  withBits(90).copyTo(train.row(3));
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(cv::NORM_HAMMING).knnMatch(query, train, knn, 2);
  std::vector<Match> expected;
  for (const auto& pair : knn) {
    if (pair[0].distance <= 0.7f * pair[1].distance && pair[0].distance < pair[1].distance) {
      expected.push_back({pair[0].queryIdx, pair[0].trainIdx, static_cast<int>(pair[0].distance)});
    }
  }
  const std::vector<Match> ours = bruteForceMatch(query, train, 0.7);
  ASSERT_EQ(ours.size(), expected.size());
  ASSERT_GT(ours.size(), 100u);
  EXPECT_EQ(ours.back().query, 300);  // the borderline pair is kept
  EXPECT_EQ(ours.back().distance, 63);
  for (size_t i = 0; i < ours.size(); ++i) {
    EXPECT_EQ(ours[i].query, expected[i].query);
    EXPECT_EQ(ours[i].train, expected[i].train);
    EXPECT_EQ(ours[i].distance, expected[i].distance);
  }
}

TEST(Matching, EmptyAndTinyInputsGiveNoMatches) {
  DescriptorMatcher matcher({0.7, MatcherMethod::brute_force});
  EXPECT_TRUE(matcher.match(cv::Mat(), randomDescriptors(10, 1)).empty());
  EXPECT_TRUE(matcher.match(randomDescriptors(10, 1), randomDescriptors(1, 2)).empty());
}

TEST(Features, NearTwinsAreDropped) {
  std::mt19937 rng(3);
  GroundFeatures f;
  f.descriptors = randomDescriptors(20, 4);
  f.descriptors.push_back(flipBits(f.descriptors.row(5), 3, rng));  // a twin of row 5
  for (int i = 0; i < 21; ++i) f.points.emplace_back(i, 0.0);
  const GroundFeatures kept = dropNearTwins(f, 10);
  EXPECT_EQ(kept.size(), 19u);  // both twins go
  for (const auto& p : kept.points) EXPECT_TRUE(p.x() != 5.0 && p.x() != 20.0);
  EXPECT_EQ(dropNearTwins(f, 0).size(), 21u);
}

TEST(Features, OrbPointsProjectToTheGround) {
  cv::Mat image(240, 320, CV_8U, cv::Scalar(90));
  cv::RNG rng(5);
  for (int i = 0; i < 150; ++i) {
    cv::circle(image, {rng.uniform(20, 300), rng.uniform(20, 220)}, rng.uniform(2, 6), cv::Scalar(rng.uniform(150, 255)), -1);
  }
  CameraIntrinsics k;
  k.width = 320, k.height = 240, k.fx = k.fy = 440.0, k.cx = 160.0, k.cy = 120.0;
  const CameraModel camera(k, defaultCameraMount(0.25));
  const ImageFeatures features = OrbExtractor(OrbSettings{}).detect(image);
  ASSERT_GT(features.keypoints.size(), 50u);
  const GroundFeatures ground = projectToGround(features, camera);
  ASSERT_EQ(ground.size(), features.keypoints.size());
  EXPECT_EQ(ground.descriptors.rows, static_cast<int>(ground.size()));
  const auto& kp = features.keypoints.front().pt;
  EXPECT_NEAR(ground.points.front().x(), (kp.x - 160.0) / 440.0 * 0.25, 1e-6);
  EXPECT_NEAR(ground.points.front().y(), -(kp.y - 120.0) / 440.0 * 0.25, 1e-6);
}

TEST(Matching, GuidedMatchingComparesOnlyNearbyFeatures) {
  // Train features on a 1 cm grid; the query sees the same features moved by a known transform. Every
  // descriptor also has an exact twin 5 cm away (a repeated pattern): brute force finds two equally good
  // candidates and keeps nothing, guided matching looks only near the prediction and keeps the right one.
  std::mt19937 rng(11);
  const Pose2 T_train_query(0.004, -0.003, 0.05);
  GroundFeatures train, query;
  const cv::Mat unique = randomDescriptors(60, 21);
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector2d p(0.01 * (i % 6), 0.01 * (i / 6));
    train.points.push_back(p);
    train.descriptors.push_back(unique.row(i));
    train.points.push_back(p + Eigen::Vector2d(0.05, 0.0));  // the twin, far away
    train.descriptors.push_back(unique.row(i));
    query.points.push_back(T_train_query.inverse() * p);
    query.descriptors.push_back(flipBits(unique.row(i), 6, rng));
  }
  const auto guided = matchNearby(query, train, T_train_query, 0.004, 0.7);
  ASSERT_EQ(guided.size(), 60u);
  for (const auto& m : guided) EXPECT_EQ(m.train, 2 * m.query);
  EXPECT_TRUE(DescriptorMatcher({0.7, MatcherMethod::brute_force}).match(query.descriptors, train.descriptors).empty());
  // A prediction off by more than the radius finds nothing to compare with.
  EXPECT_TRUE(matchNearby(query, train, Pose2(0.3, 0.3, 0.0) * T_train_query, 0.004, 0.7).empty());
}

TEST(NearestDescriptors, EveryKernelGivesTheScalarAnswerWithTiesAndPartialBlocks) {
  std::mt19937 rng(5);
  std::vector<HammingKernel> kernels = supportedHammingKernels();
  ASSERT_EQ(kernels.front(), HammingKernel::scalar);
  for (const int train_rows : {1, 2, 7, 8, 9, 31, 1503}) {
    cv::Mat train = randomDescriptors(train_rows, static_cast<unsigned>(11 + train_rows));
    if (train_rows > 8) train.row(2).copyTo(train.row(train_rows - 1));  // an exact twin: tied distances
    cv::Mat query;
    for (int i = 0; i < 60; ++i) query.push_back(flipBits(train.row(i % train_rows), i % 40, rng));
    query.push_back(randomDescriptors(20, 3));
    const std::vector<TwoNearest> expected = twoNearest(query, train, HammingKernel::scalar);
    for (const HammingKernel kernel : kernels) {
      const std::vector<TwoNearest> got = twoNearest(query, train, kernel);
      ASSERT_EQ(got.size(), expected.size());
      for (size_t q = 0; q < got.size(); ++q) {
        EXPECT_EQ(got[q].best, expected[q].best) << "kernel " << int(kernel) << " rows " << train_rows << " query " << q;
        EXPECT_EQ(got[q].best_distance, expected[q].best_distance) << int(kernel) << " " << train_rows << " " << q;
        EXPECT_EQ(got[q].second_distance, expected[q].second_distance) << int(kernel) << " " << train_rows << " " << q;
      }
    }
    // A query equal to train row 0 finds it at distance 0; with one train row there is no second.
    const TwoNearest own = twoNearest(train.row(0), train)[0];
    EXPECT_EQ(own.best, 0);
    EXPECT_EQ(own.best_distance, 0);
    if (train_rows == 1) {
      EXPECT_EQ(own.second_distance, 257);
    }
  }
  // The twin: row 2 and the last row of the 1503-row set are equal; the lower row wins, the second is the tie.
  const cv::Mat train = randomDescriptors(1503, 11 + 1503);
  cv::Mat with_twin = train.clone();
  train.row(2).copyTo(with_twin.row(1502));
  for (const HammingKernel kernel : kernels) {
    const TwoNearest n = twoNearest(train.row(2), with_twin, kernel)[0];
    EXPECT_EQ(n.best, 2) << int(kernel);
    EXPECT_EQ(n.best_distance, 0) << int(kernel);
    EXPECT_EQ(n.second_distance, 0) << int(kernel);
  }
}
