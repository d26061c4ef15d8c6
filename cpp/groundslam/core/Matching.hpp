#pragma once
// Paper §III-B1: binary descriptors matched by Hamming distance, two nearest neighbours, Lowe's ratio test.

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace groundslam {

struct MatcherSettings {
  double ratio = 0.7;                  ///< lambda: keep a match when f0 <= lambda * f1
  std::string method = "brute_force";  ///< brute_force | lsh (FLANN multi-probe LSH)
};

struct Match {
  int query = 0;     ///< row in the query descriptors
  int train = 0;     ///< row in the train descriptors
  int distance = 0;  ///< Hamming distance, bits
};

class DescriptorMatcher {
 public:
  explicit DescriptorMatcher(const MatcherSettings& settings);
  /// For each query descriptor, its nearest train descriptor when it passes the ratio test.
  std::vector<Match> match(const cv::Mat& query, const cv::Mat& train) const;

 private:
  MatcherSettings settings_;
};

}  // namespace groundslam
