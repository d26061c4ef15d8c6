#include "groundslam/eval/LoopClosureMetrics.hpp"

#include "groundslam/eval/NumberText.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include <opencv2/imgproc.hpp>

namespace groundslam {
namespace {

constexpr double kWrongTranslationM = 0.02;
constexpr double kWrongRotationDeg = 2.0;

std::vector<cv::Point2f> inWorld(const std::vector<Eigen::Vector2d>& footprint, const Pose2& T_world_robot) {
  std::vector<cv::Point2f> points, hull;
  for (const auto& p : footprint) {
    const Eigen::Vector2d w = T_world_robot * p;
    points.emplace_back(static_cast<float>(w.x()), static_cast<float>(w.y()));
  }
  // intersectConvexConvex needs strictly convex polygons: the hull drops the border's collinear points.
  cv::convexHull(points, hull);
  return hull;
}

}  // namespace

double footprintOverlap(const std::vector<Eigen::Vector2d>& footprint, const Pose2& T_world_a, const Pose2& T_world_b) {
  if (footprint.size() < 3) return 0.0;
  std::vector<cv::Point2f> a = inWorld(footprint, T_world_a), b = inWorld(footprint, T_world_b), intersection;
  return static_cast<double>(cv::intersectConvexConvex(a, b, intersection, true));
}

CandidateTruth candidateTruth(const LoopCandidate& candidate, const Pose2& true_T_world_a, const Pose2& true_T_world_b,
                              const std::vector<Eigen::Vector2d>& footprint) {
  CandidateTruth truth;
  truth.distance_m = (true_T_world_a.translation() - true_T_world_b.translation()).norm();
  truth.footprints_overlap = footprintOverlap(footprint, true_T_world_a, true_T_world_b) > 0.0;
  const Pose2 true_T_a_b = between(true_T_world_a, true_T_world_b);
  truth.translation_error_m = (candidate.T_a_b.translation() - true_T_a_b.translation()).norm();
  truth.rotation_error_deg = std::abs(wrapAngle(candidate.T_a_b.theta - true_T_a_b.theta)) * 180.0 / M_PI;
  return truth;
}

std::vector<std::optional<CandidateTruth>> candidateTruths(const std::vector<LoopCandidate>& candidates,
                                                           const std::vector<double>& frame_timestamps,
                                                           const std::vector<StampedPose>& groundtruth,
                                                           const std::vector<Eigen::Vector2d>& footprint) {
  std::map<double, Pose2> truth_at;
  for (const auto& p : groundtruth) truth_at[p.timestamp] = p.T_world_robot;
  auto truthOf = [&](int frame) -> std::optional<Pose2> {
    if (frame < 0 || static_cast<size_t>(frame) >= frame_timestamps.size()) return std::nullopt;
    const auto it = truth_at.find(frame_timestamps[static_cast<size_t>(frame)]);
    if (it == truth_at.end()) return std::nullopt;
    return it->second;
  };
  std::vector<std::optional<CandidateTruth>> truths;
  for (const auto& c : candidates) {
    const auto a = truthOf(c.frame_a), b = truthOf(c.frame_b);
    truths.push_back(a && b ? std::optional<CandidateTruth>(candidateTruth(c, *a, *b, footprint)) : std::nullopt);
  }
  return truths;
}

LoopClosureMetrics summariseLoopClosures(const std::vector<LoopCandidate>& candidates,
                                         const std::vector<std::optional<CandidateTruth>>& truths) {
  LoopClosureMetrics m;
  double sum_t = 0.0, sum_r = 0.0, max_t = 0.0, max_r = 0.0;
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (!truths[i]) continue;
    const CandidateTruth& truth = *truths[i];
    ++m.verified;
    m.true_candidates += truth.footprints_overlap ? 1 : 0;
    if (!candidates[i].accepted()) continue;
    ++m.accepted;
    m.true_positives += truth.footprints_overlap ? 1 : 0;
    // An error that could not be measured (NaN) is not a right one.
    const bool wrong = !truth.footprints_overlap || !(truth.translation_error_m <= kWrongTranslationM) ||
                       !(truth.rotation_error_deg <= kWrongRotationDeg);
    m.wrong_accepted += wrong ? 1 : 0;
    sum_t += truth.translation_error_m;
    sum_r += truth.rotation_error_deg;
    max_t = std::isnan(truth.translation_error_m) ? truth.translation_error_m : std::max(max_t, truth.translation_error_m);
    max_r = std::isnan(truth.rotation_error_deg) ? truth.rotation_error_deg : std::max(max_r, truth.rotation_error_deg);
  }
  if (m.accepted > 0) {
    m.precision = static_cast<double>(m.true_positives) / m.accepted;
    m.mean_translation_error_m = sum_t / m.accepted;
    m.mean_rotation_error_deg = sum_r / m.accepted;
    m.max_translation_error_m = max_t;
    m.max_rotation_error_deg = max_r;
  }
  if (m.true_candidates > 0) m.recall = static_cast<double>(m.true_positives) / m.true_candidates;
  return m;
}

std::string loopMetricsToJson(const LoopClosureMetrics& m) {
  return "{\n  \"verified\": " + std::to_string(m.verified) + ",\n  \"accepted\": " + std::to_string(m.accepted) +
         ",\n  \"true_candidates\": " + std::to_string(m.true_candidates) + ",\n  \"true_positives\": " +
         std::to_string(m.true_positives) + ",\n  \"wrong_accepted\": " + std::to_string(m.wrong_accepted) +
         ",\n  \"precision\": " + jsonNumber(m.precision, 6) + ",\n  \"recall\": " + jsonNumber(m.recall, 6) +
         ",\n  \"mean_translation_error_m\": " + jsonNumber(m.mean_translation_error_m, 9) +
         ",\n  \"max_translation_error_m\": " + jsonNumber(m.max_translation_error_m, 9) +
         ",\n  \"mean_rotation_error_deg\": " + jsonNumber(m.mean_rotation_error_deg, 6) +
         ",\n  \"max_rotation_error_deg\": " + jsonNumber(m.max_rotation_error_deg, 6) + "\n}";
}

std::string loopMetricsToText(const LoopClosureMetrics& m) {
  return "loop closures         " + std::to_string(m.accepted) + " accepted of " + std::to_string(m.verified) +
         " verified candidates (" + std::to_string(m.wrong_accepted) + " wrong)\n" +
         "  precision / recall  " + textNumber(m.precision, 3) + " / " + textNumber(m.recall, 3) +
         "  (true = footprints overlap)\n" + "  transform error     mean " + textNumber(m.mean_translation_error_m, 2, 1000.0) +
         " mm, " + textNumber(m.mean_rotation_error_deg, 3) + " deg; max " + textNumber(m.max_translation_error_m, 2, 1000.0) +
         " mm, " + textNumber(m.max_rotation_error_deg, 3) + " deg\n";
}

}  // namespace groundslam
