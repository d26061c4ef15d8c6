#include "groundslam/core/Matching.hpp"

#include "groundslam/core/NearestDescriptors.hpp"

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
  // Every pair compared (vector popcount where the CPU has it, see NearestDescriptors.hpp); the two nearest
  // kept for the ratio test.
  std::vector<Match> matches;
  const std::vector<TwoNearest> nearest = twoNearest(query, train);
  for (int q = 0; q < query.rows; ++q) {
    const TwoNearest& n = nearest[static_cast<size_t>(q)];
    const int second_distance = std::min(n.second_distance, 256);  // a lone train descriptor has no close rival
    // Lowe's ratio test (paper eq. 5) in float, as on OpenCV's DMatch distances (63 <= 0.7f * 90 holds in
    // float, not in double); best < second also rejects two equally good candidates.
    const float f0 = static_cast<float>(n.best_distance), f1 = static_cast<float>(second_distance);
    if (n.best >= 0 && f0 <= static_cast<float>(ratio) * f1 && f0 < f1) matches.push_back({q, n.best, n.best_distance});
  }
  return matches;
}

DescriptorMatcher::DescriptorMatcher(const MatcherSettings& settings) : settings_(settings) {}

std::vector<Match> DescriptorMatcher::match(const cv::Mat& query, const cv::Mat& train) const {
  std::vector<Match> matches;
  if (query.empty() || train.rows < 2) return matches;
  std::vector<std::vector<cv::DMatch>> knn;
  if (settings_.method == MatcherMethod::lsh) {
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

/// Train features bucketed in square cells of the search radius over their bounding box (a dense array of
/// cells, filled by counting sort): a query looks at its 3x3 cells.
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector2d>& points, double cell_m) : cell_m_(cell_m) {
    if (points.empty()) return;
    origin_ = points.front();
    Eigen::Vector2d hi = points.front();
    for (const Eigen::Vector2d& p : points) origin_ = origin_.cwiseMin(p), hi = hi.cwiseMax(p);
    // At most 1024 cells a side: a radius far below the footprint gets wider cells (still >= the radius, so
    // the 3x3 cells around a query cover it).
    cell_m_ = std::max({cell_m_, (hi.x() - origin_.x()) / 1000.0, (hi.y() - origin_.y()) / 1000.0, 1e-12});
    width_ = static_cast<long>((hi.x() - origin_.x()) / cell_m_) + 1;
    height_ = static_cast<long>((hi.y() - origin_.y()) / cell_m_) + 1;
    start_.assign(static_cast<size_t>(width_ * height_ + 1), 0);
    std::vector<long> cell_of(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      cell_of[i] = cellIndex(points[i]);
      ++start_[static_cast<size_t>(cell_of[i]) + 1];
    }
    for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    indices_.resize(points.size());
    std::vector<int> next(start_.begin(), start_.end() - 1);
    for (size_t i = 0; i < points.size(); ++i) indices_[static_cast<size_t>(next[static_cast<size_t>(cell_of[i])]++)] = static_cast<int>(i);
  }
  template <class Visit>
  void forEachNear(const Eigen::Vector2d& p, Visit&& visit) const {
    if (indices_.empty()) return;
    const double fx = std::floor((p.x() - origin_.x()) / cell_m_), fy = std::floor((p.y() - origin_.y()) / cell_m_);
    if (fx < -1.0 || fy < -1.0 || fx > static_cast<double>(width_) || fy > static_cast<double>(height_)) return;
    const long cx = static_cast<long>(fx), cy = static_cast<long>(fy);
    for (long y = std::max(0L, cy - 1); y <= std::min(height_ - 1, cy + 1); ++y) {
      for (long x = std::max(0L, cx - 1); x <= std::min(width_ - 1, cx + 1); ++x) {
        const auto cell = static_cast<size_t>(y * width_ + x);
        for (int k = start_[cell]; k < start_[cell + 1]; ++k) visit(indices_[static_cast<size_t>(k)]);
      }
    }
  }

 private:
  long cellIndex(const Eigen::Vector2d& p) const {
    const long x = std::min(width_ - 1, static_cast<long>((p.x() - origin_.x()) / cell_m_));
    const long y = std::min(height_ - 1, static_cast<long>((p.y() - origin_.y()) / cell_m_));
    return y * width_ + x;
  }
  double cell_m_;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  long width_ = 0, height_ = 0;
  std::vector<int> start_;    ///< cell c holds indices_[start_[c] .. start_[c + 1])
  std::vector<int> indices_;  ///< point indices ordered by cell
};

}  // namespace

std::vector<Match> matchNearby(const GroundFeatures& query, const GroundFeatures& train, const Pose2& T_train_query,
                               double radius_m, double ratio) {
  std::vector<Match> matches;
  if (query.size() == 0 || train.size() == 0) return matches;
  const PointGrid grid(train.points, radius_m);
  const double radius2 = radius_m * radius_m;
  const Eigen::Matrix2d R = T_train_query.rotation();  // once, not per point
  const Eigen::Vector2d t = T_train_query.translation();
  for (size_t q = 0; q < query.size(); ++q) {
    const Eigen::Vector2d predicted = R * query.points[q] + t;
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
