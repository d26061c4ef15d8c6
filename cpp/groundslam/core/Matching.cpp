#include "groundslam/core/Matching.hpp"

#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>

namespace groundslam {

DescriptorMatcher::DescriptorMatcher(const MatcherSettings& settings) : settings_(settings) {}

std::vector<Match> DescriptorMatcher::match(const cv::Mat& query, const cv::Mat& train) const {
  std::vector<Match> matches;
  if (query.empty() || train.rows < 2) return matches;
  std::vector<std::vector<cv::DMatch>> knn;
  if (settings_.method == "lsh") {
    // 12 tables of 20-bit keys, multi-probe level 2: the usual setting for 256-bit ORB.
    cv::FlannBasedMatcher lsh(cv::makePtr<cv::flann::LshIndexParams>(12, 20, 2));
    lsh.knnMatch(query, train, knn, 2);
  } else {
    cv::BFMatcher(cv::NORM_HAMMING).knnMatch(query, train, knn, 2);
  }
  constexpr float kFarthest = 256.0f;  // bits in an ORB descriptor
  for (const auto& pair : knn) {
    if (pair.empty()) continue;
    // LSH finds only descriptors that share a hash bucket: a lone candidate has no close rival.
    const float f0 = pair[0].distance, f1 = pair.size() > 1 ? pair[1].distance : kFarthest;
    // Lowe's ratio test (paper eq. 5); f0 < f1 also rejects two equally good candidates at distance 0.
    if (f0 <= static_cast<float>(settings_.ratio) * f1 && f0 < f1) {
      matches.push_back({pair[0].queryIdx, pair[0].trainIdx, static_cast<int>(f0)});
    }
  }
  return matches;
}

}  // namespace groundslam
