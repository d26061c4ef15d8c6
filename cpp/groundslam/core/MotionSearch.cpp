#include "groundslam/core/MotionSearch.hpp"

#include <algorithm>
#include <cmath>

namespace groundslam {

std::optional<MotionSearchResult> searchMotion(const GroundFeatures& query, const GroundFeatures& train,
                                               const std::vector<Pose2>& hypotheses, const MotionSearchSettings& settings,
                                               const FitSettings& fitting, const MatchFilter& filter) {
  // Matching is cheap, fitting is not: hypotheses are fitted in order of their matches, and those with too few
  // matches to beat the best fit or to rival it (inliers are at most the matches) are not fitted at all.
  std::vector<std::pair<const Pose2*, std::vector<Match>>> gathered;
  for (const Pose2& hypothesis : hypotheses) {
    std::vector<Match> matches = matchNearby(query, train, hypothesis, settings.radius_m, settings.ratio);
    matches.erase(std::remove_if(matches.begin(), matches.end(), [&](const Match& m) { return m.distance > settings.max_hamming; }),
                  matches.end());
    if (filter) matches = filter(std::move(matches));
    if (matches.size() >= static_cast<size_t>(fitting.min_inliers)) gathered.emplace_back(&hypothesis, std::move(matches));
  }
  std::stable_sort(gathered.begin(), gathered.end(), [](const auto& a, const auto& b) { return a.second.size() > b.second.size(); });
  std::vector<MotionSearchResult> found;
  int most_inliers = 0;
  for (const auto& [hypothesis, matches] : gathered) {
    const double could_have = static_cast<double>(matches.size());
    if (could_have < static_cast<double>(most_inliers) && could_have <= settings.max_rival_share * most_inliers) break;
    std::vector<Eigen::Vector2d> train_points, query_points;
    for (const Match& m : matches) {
      train_points.push_back(train.points[static_cast<size_t>(m.train)]);
      query_points.push_back(query.points[static_cast<size_t>(m.query)]);
    }
    const TransformPrior around{*hypothesis, 2.0 * settings.radius_m, settings.turn_margin_rad};
    RigidEstimate fit = fitRigidTransform(train_points, query_points, fitting, around);
    if (!fit.ok()) continue;
    most_inliers = std::max(most_inliers, fit.inliers);
    found.push_back({std::move(fit), 0});
  }
  if (found.empty()) return std::nullopt;
  const auto best = std::max_element(found.begin(), found.end(),
                                     [](const auto& a, const auto& b) { return a.fit.inliers < b.fit.inliers; });
  for (const MotionSearchResult& other : found) {
    const Pose2 difference = best->fit.T_target_source.inverse() * other.fit.T_target_source;
    if (difference.translation().norm() > settings.distinct_m || std::abs(difference.theta) > settings.distinct_rad) {
      best->rival_inliers = std::max(best->rival_inliers, other.fit.inliers);
    }
  }
  if (static_cast<double>(best->rival_inliers) > settings.max_rival_share * static_cast<double>(best->fit.inliers)) return std::nullopt;
  return std::move(*best);
}

std::vector<Pose2> turnHypotheses(const Pose2& step, double turn_step_rad) {
  std::vector<Pose2> hypotheses;
  if (!(turn_step_rad > 0.0)) return hypotheses;
  const int count = static_cast<int>(std::ceil(2.0 * M_PI / turn_step_rad - 1e-9));
  for (int i = 0; i < count; ++i) hypotheses.emplace_back(step.x, step.y, -M_PI + (i + 1) * turn_step_rad);
  return hypotheses;
}

}  // namespace groundslam
