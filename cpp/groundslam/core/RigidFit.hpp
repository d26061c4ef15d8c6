#pragma once
// Paper §III-B2: the SE(2) transform that maps one set of ground points onto its matches, under a
// robust M-estimator (Huber, Cauchy or Geman-McClure) solved by iteratively reweighted least squares, with its covariance.
// The paper starts the solver at identity, which fails for large rotations; we start it from a
// 2-point RANSAC estimate, so any heading works (revisits at 180 degrees included).

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "groundslam/core/Pose2.hpp"

namespace groundslam {

/// The robust M-estimator of the fit (paper §III-B2).
enum class RobustLoss { huber, cauchy, geman_mcclure };

struct FitSettings {
  RobustLoss loss = RobustLoss::huber;
  double loss_scale_m = 0.0005;  ///< residual at which the robust loss starts to down-weight, metres
  int min_inliers = 12;          ///< fewer inliers than this is a failed fit
  double ransac_inlier_m = 0.002;  ///< RANSAC inlier distance, metres
  /// A consensus whose points spread less than this many RANSAC inlier distances (one standard deviation) across
  /// their narrowest direction is degenerate: matches along one edge slide along it.
  double min_spread_inliers = 2.0;
  int ransac_iterations = 200;   ///< most RANSAC hypotheses (fewer when the inlier ratio allows)
  int seed = 42;                 ///< seed of the RANSAC sampler
  bool measure_ambiguity = false;  ///< run every RANSAC hypothesis and report the best rival transform's support
  /// When set, a rival must be shifted by over 1 cm with a rotation within this (a repetition of the floor);
  /// unset, any transform over 1 cm or 3 degrees away is a rival.
  std::optional<double> rival_max_rotation_rad;
  /// > 0: a rival's support counts only matches whose two points lie farther apart than this. Matches that
  /// stayed (nearly) in place are what the camera's own artifacts give (a shadow's edge, glare, a bumper), and
  /// a transform they support is not a repetition of the floor.
  double rival_min_motion_m = 0.0;
};

/// What is already believed about the transform: RANSAC then only considers hypotheses within the window.
/// On a repetitive floor this picks the right repetition out of several that the matches support equally.
struct TransformPrior {
  Pose2 T_target_source;
  double radius_m = 0.0;    ///< largest translation difference considered
  double radius_rad = 0.0;  ///< largest rotation difference considered
};

/// `ambiguous`: set by callers that refuse a fit another transform explains almost as well (repetitive floors);
/// `implausible_motion`: set by callers that refuse a motion far from the one the robot was making;
/// `still`: set by callers that refuse a fit leaving every match in place while the images show the ground moving.
enum class FitStatus { ok, too_few_matches, too_few_inliers, degenerate, solver_failed, ambiguous, implausible_motion, still };
const char* fitStatusName(FitStatus status);
/// The fit had too little evidence (too few matches or inliers, degenerate), not a motion refused for what it said.
bool tooLittleEvidence(FitStatus status);

struct RigidEstimate {
  FitStatus status = FitStatus::too_few_matches;
  Pose2 T_target_source;        ///< maps source points onto target points: p_target = T * p_source
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  ///< of (x, y, theta); m^2, m rad, rad^2
  int inliers = 0;              ///< matches within the RANSAC inlier distance of the final fit
  double rms_residual_m = 0.0;  ///< over the inliers
  /// Support of the best RANSAC hypothesis far from the chosen one (> 1 cm or > 3 degrees away); only with
  /// measure_ambiguity. A repetitive floor (tiles) fits several offsets almost equally well.
  int rival_inliers = 0;
  /// The strongest RANSAC hypotheses far from the chosen one and from each other (strongest first, at most
  /// kMaxRivals; only with measure_ambiguity): the other repetitions a caller may check by other means.
  std::vector<Pose2> rivals;
  static constexpr size_t kMaxRivals = 3;
  bool ok() const { return status == FitStatus::ok; }
  /// rival_inliers / inliers: near 1 when another transform explains the matches as well.
  double ambiguity() const { return inliers > 0 ? static_cast<double>(rival_inliers) / inliers : 1.0; }
  /// The paper's covariance score (§III-C3): log10 of the largest eigenvalue of the covariance.
  double covarianceScore() const;
};

/// Fits T with target[i] ~ T * source[i] for matched pairs. Failure is a status, never an exception (only a
/// `settings.loss` that is none of RobustLoss's values, which validateConfig refuses, throws std::invalid_argument).
RigidEstimate fitRigidTransform(const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source,
                                const FitSettings& settings, const std::optional<TransformPrior>& prior = std::nullopt);

/// The robust refinement alone, from a transform already known to within a few RANSAC inlier distances (a
/// prediction, or the same matches' fit before the points were re-projected): every match within three inlier
/// distances of `initial` enters the M-estimator. Same status, covariance and inlier count as fitRigidTransform;
/// no rival is measured. For callers that know the answer roughly, a fraction of a full fit's cost.
RigidEstimate refineRigidTransform(const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source,
                                   const Pose2& initial, const FitSettings& settings);

/// The least-squares T with target[i] ~ T * source[i] over all pairs (2-D Kabsch, no robust loss): for exact
/// correspondences such as one image's points projected two ways. Identity when there are none.
Pose2 leastSquaresRigid(const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source);

/// Whether a motion with this (x, y, theta) covariance is within `within_m` and `within_rad` of the truth at
/// `sigmas` standard deviations: its heading's, and its position's along the worst direction (x and y correlated
/// make one direction worse than either axis).
bool withinAtSigmas(const Eigen::Matrix3d& covariance, double sigmas, double within_m, double within_rad);

/// Whether the fit shows the floor repeating: a rival transform (measure_ambiguity) with at least `min_inliers`
/// inliers, what a fit itself needs. A weak fit's rivals of a few matches agreeing by chance show nothing.
bool showsARepetition(const RigidEstimate& fit, int min_inliers);

}  // namespace groundslam
