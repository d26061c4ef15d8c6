#include "groundslam/eval/LoopClosureMetrics.hpp"

#include "groundslam/eval/NumberText.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace groundslam {
namespace {

constexpr double kWrongTranslationM = 0.02;
constexpr double kWrongRotationDeg = 2.0;

using Polygon = std::vector<Eigen::Vector2d>;

double signedArea(const Polygon& polygon) {
  double twice = 0.0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d& p = polygon[i];
    const Eigen::Vector2d& q = polygon[(i + 1) % polygon.size()];
    twice += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * twice;
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Counter-clockwise convex hull (Andrew's monotone chain); a distorted border may bulge inwards a little.
Polygon convexHull(Polygon points) {
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
    return p.x() < q.x() || (p.x() == q.x() && p.y() < q.y());
  });
  if (points.size() < 3) return points;
  Polygon hull(2 * points.size());
  size_t k = 0;
  for (size_t i = 0; i < points.size(); ++i) {  // lower chain
    while (k >= 2 && cross(hull[k - 1] - hull[k - 2], points[i] - hull[k - 2]) <= 0.0) --k;
    hull[k++] = points[i];
  }
  for (size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && cross(hull[k - 1] - hull[k - 2], points[i] - hull[k - 2]) <= 0.0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);
  return hull;
}

/// The part of `subject` on the left of the directed line a -> b (Sutherland-Hodgman, one edge).
Polygon clipLeftOf(const Polygon& subject, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  Polygon kept;
  const Eigen::Vector2d edge = b - a;
  for (size_t i = 0; i < subject.size(); ++i) {
    const Eigen::Vector2d& p = subject[i];
    const Eigen::Vector2d& q = subject[(i + 1) % subject.size()];
    const double side_p = cross(edge, p - a), side_q = cross(edge, q - a);
    if (side_p >= 0.0) kept.push_back(p);
    if ((side_p >= 0.0) != (side_q >= 0.0)) kept.push_back(p + (q - p) * (side_p / (side_p - side_q)));
  }
  return kept;
}

}  // namespace

double footprintOverlap(const std::vector<Eigen::Vector2d>& footprint, const Pose2& T_world_a, const Pose2& T_world_b) {
  // Exact clipping in double precision: OpenCV's intersectConvexConvex (float points) returned 0 for footprints
  // half overlapping along a lawnmower lane, whose long edges lie on nearly the same lines.
  if (footprint.size() < 3) return 0.0;
  Polygon a, b;
  for (const Eigen::Vector2d& p : footprint) a.push_back(T_world_a * p), b.push_back(T_world_b * p);
  b = convexHull(b);
  Polygon overlap = convexHull(a);
  for (size_t i = 0; i < b.size() && !overlap.empty(); ++i) {
    const Eigen::Vector2d& from = b[i];
    const Eigen::Vector2d& to = b[(i + 1) % b.size()];
    if ((to - from).squaredNorm() > 0.0) overlap = clipLeftOf(overlap, from, to);
  }
  return overlap.size() < 3 ? 0.0 : std::abs(signedArea(overlap));
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
