#pragma once
// Not in the paper: finding a motion the features alone cannot, by trying the motions the robot can have made.
// After a turn on the spot of a quarter turn over a weak floor, or a few frames dropped without a trace, too few
// matches survive brute-force matching's ratio test (under a shadow that turns with the heading, ORB's own
// orientation is noisy). Here each hypothesis puts every feature of one image where it predicts it in the other;
// features are compared only within a small window there, and a pair further apart than a bound in Hamming bits
// is no match (a lone feature in the window passes any ratio test). Only near the true motion do enough pairs
// agree; the best fit must clearly beat every fit found from a distinct hypothesis.

#include <functional>
#include <optional>
#include <vector>

#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/Pose2.hpp"
#include "groundslam/core/RigidFit.hpp"

namespace groundslam {

struct MotionSearchSettings {
  double radius_m = 0.008;   ///< features compared within this of where a hypothesis puts them
  double ratio = 0.7;        ///< ratio test among the features in the window
  int max_hamming = 80;      ///< a closer pair only is a match, bits
  double turn_margin_rad = 5.0 * 0.017453292519943295;  ///< a fit turns at most this far from its hypothesis
  /// Fits further apart than these are distinct: no distinct one may have more than max_rival_share of the best's
  /// inliers.
  double distinct_m = 0.01;
  double distinct_rad = 10.0 * 0.017453292519943295;
  double max_rival_share = 0.5;
};

struct MotionSearchResult {
  RigidEstimate fit;           ///< T_train_query: maps query points onto train points
  int rival_inliers = 0;       ///< the most inliers of a distinct hypothesis's fit
};

/// Filters a hypothesis's matches before the fit (e.g. the robot's own artifacts); identity when empty.
using MatchFilter = std::function<std::vector<Match>(std::vector<Match>)>;

/// Each hypothesis T_train_query guides the matching; its matches are fitted around it (`fitting`; a hypothesis
/// whose matches are too few to beat or rival the best fit is not fitted). The fit with the most inliers, when it
/// has at least fitting.min_inliers and no distinct fit has more than max_rival_share of them; otherwise nothing.
/// Failure is data, never an exception.
std::optional<MotionSearchResult> searchMotion(const GroundFeatures& query, const GroundFeatures& train,
                                               const std::vector<Pose2>& hypotheses, const MotionSearchSettings& settings,
                                               const FitSettings& fitting, const MatchFilter& filter = {});

/// Hypotheses for a turn on the spot: `step` followed by every turn in steps of `turn_step_rad` over a full circle.
std::vector<Pose2> turnHypotheses(const Pose2& step, double turn_step_rad);

}  // namespace groundslam
