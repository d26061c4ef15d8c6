#pragma once
// Paper §III-B1: binary descriptors matched by Hamming distance, two nearest neighbours, Lowe's ratio test.

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Pose2.hpp"

namespace groundslam {

/// How descriptors find their two nearest neighbours: exhaustively, or with FLANN's multi-probe LSH.
enum class MatcherMethod { brute_force, lsh };

struct MatcherSettings {
  double ratio = 0.7;                  ///< lambda: keep a match when f0 <= lambda * f1
  MatcherMethod method = MatcherMethod::brute_force;
  double guided_odometry_radius_m = 0.0;  ///< > 0: odometry compares features within this of the constant-velocity prediction (faster, see docs/benchmarks.md); 0 = brute force
  double guided_min_inlier_fraction = 0.25;  ///< fewer guided inliers (fraction of keypoints) falls back to brute force
};

struct Match {
  int query = 0;     ///< row in the query descriptors
  int train = 0;     ///< row in the train descriptors
  int distance = 0;  ///< Hamming distance, bits
};

/// Brute-force 2-nearest-neighbour Hamming matching of 256-bit descriptors with Lowe's ratio test: the
/// same matches as OpenCV's BFMatcher + knnMatch(2) + the ratio test, in a third of the time.
std::vector<Match> bruteForceMatch(const cv::Mat& query, const cv::Mat& train, double ratio);

class DescriptorMatcher {
 public:
  explicit DescriptorMatcher(const MatcherSettings& settings);
  /// For each query descriptor, its nearest train descriptor when it passes the ratio test.
  std::vector<Match> match(const cv::Mat& query, const cv::Mat& train) const;

 private:
  MatcherSettings settings_;
};

/// Guided matching: each query feature is compared only with the train features lying within `radius_m`
/// of where `T_train_query` predicts it, with the same ratio test among those. When the transform is
/// roughly known (a loop candidate checked against the map's estimate) this costs a fraction of brute
/// force and cannot pair a feature with a lookalike far away.
std::vector<Match> matchNearby(const GroundFeatures& query, const GroundFeatures& train, const Pose2& T_train_query,
                               double radius_m, double ratio);

}  // namespace groundslam
