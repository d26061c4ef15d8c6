#include "groundslam/core/Matching.hpp"

#include "groundslam/core/Hamming.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <unordered_map>

#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>

namespace groundslam {

std::vector<Match> bruteForceMatch(const cv::Mat& query, const cv::Mat& train, double ratio) {
  // Every pair compared (hardware popcount: about 2 ns a pair); the two nearest kept for the ratio test.
  std::vector<Match> matches;
  for (int q = 0; q < query.rows; ++q) {
    const std::uint8_t* descriptor = query.ptr<std::uint8_t>(q);
    int best = -1, best_distance = 257, second_distance = 257;
    for (int t = 0; t < train.rows; ++t) {
      const int d = hammingDistance256(descriptor, train.ptr<std::uint8_t>(t));
      if (d < best_distance) {
        second_distance = best_distance;
        best_distance = d, best = t;
      } else if (d < second_distance) {
        second_distance = d;
      }
    }
    second_distance = std::min(second_distance, 256);  // a lone train descriptor has no close rival
    // Lowe's ratio test (paper eq. 5); best < second also rejects two equally good candidates.
    if (best >= 0 && best_distance <= ratio * second_distance && best_distance < second_distance) {
      matches.push_back({q, best, best_distance});
    }
  }
  return matches;
}

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
    return bruteForceMatch(query, train, settings_.ratio);
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

namespace {

/// Train features bucketed in square cells of the search radius: a query looks at its 3x3 cells.
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector2d>& points, double cell_m) : cell_m_(cell_m) {
    for (size_t i = 0; i < points.size(); ++i) cells_[key(points[i])].push_back(static_cast<int>(i));
  }
  template <class Visit>
  void forEachNear(const Eigen::Vector2d& p, Visit&& visit) const {
    const auto [cx, cy] = cellOf(p);
    for (long dx = -1; dx <= 1; ++dx) {
      for (long dy = -1; dy <= 1; ++dy) {
        const auto it = cells_.find(pack(cx + dx, cy + dy));
        if (it == cells_.end()) continue;
        for (int index : it->second) visit(index);
      }
    }
  }

 private:
  std::pair<long, long> cellOf(const Eigen::Vector2d& p) const {
    return {static_cast<long>(std::floor(p.x() / cell_m_)), static_cast<long>(std::floor(p.y() / cell_m_))};
  }
  static long long pack(long x, long y) { return (static_cast<long long>(x) << 32) ^ (static_cast<long long>(y) & 0xffffffffLL); }
  long long key(const Eigen::Vector2d& p) const {
    const auto [x, y] = cellOf(p);
    return pack(x, y);
  }
  double cell_m_;
  std::unordered_map<long long, std::vector<int>> cells_;
};

}  // namespace

std::vector<Match> matchNearby(const GroundFeatures& query, const GroundFeatures& train, const Pose2& T_train_query,
                               double radius_m, double ratio) {
  std::vector<Match> matches;
  if (query.size() == 0 || train.size() == 0) return matches;
  const PointGrid grid(train.points, radius_m);
  const double radius2 = radius_m * radius_m;
  Eigen::Matrix2d rotation;  // computed once, not per point
  rotation << std::cos(T_train_query.theta), -std::sin(T_train_query.theta), std::sin(T_train_query.theta),
      std::cos(T_train_query.theta);
  for (size_t q = 0; q < query.size(); ++q) {
    const Eigen::Vector2d predicted = rotation * query.points[q] + T_train_query.translation();
    const std::uint8_t* descriptor = query.descriptors.ptr<std::uint8_t>(static_cast<int>(q));
    int best = -1, best_distance = 257, second_distance = 256;  // a lone candidate has no close rival
    grid.forEachNear(predicted, [&](int t) {
      if ((train.points[static_cast<size_t>(t)] - predicted).squaredNorm() > radius2) return;
      const int d = hammingDistance256(descriptor, train.descriptors.ptr<std::uint8_t>(t));
      if (d < best_distance) {
        second_distance = best_distance;
        best_distance = d, best = t;
      } else if (d < second_distance) {
        second_distance = d;
      }
    });
    second_distance = std::min(second_distance, 256);
    if (best >= 0 && best_distance <= ratio * second_distance && best_distance < second_distance) {
      matches.push_back({static_cast<int>(q), best, best_distance});
    }
  }
  return matches;
}

}  // namespace groundslam
