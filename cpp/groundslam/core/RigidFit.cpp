#include "groundslam/core/RigidFit.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <stdexcept>
#include <string>

namespace groundslam {
namespace {

/// rho'(s) of the robust loss at a squared residual s, where rho(s) = s near zero (Ceres's convention): the
/// weight of a match in iteratively reweighted least squares.
double lossWeight(RobustLoss loss, double scale, double s) {
  const double a2 = scale * scale;
  switch (loss) {
    case RobustLoss::huber: return s <= a2 ? 1.0 : scale / std::sqrt(s);  // rho = 2 a sqrt(s) - a^2 beyond a
    case RobustLoss::cauchy: return 1.0 / (1.0 + s / a2);                  // rho = a^2 log(1 + s / a^2)
    case RobustLoss::geman_mcclure: {                                      // rho = s a^2 / (s + a^2): bounded
      const double d = s + a2;
      return a2 * a2 / (d * d);
    }
  }
  throw std::invalid_argument("odometry.loss: unknown robust loss " + std::to_string(static_cast<int>(loss)));
}

/// The exact minimiser of sum w_i |R(theta) source_i + t - target_i|^2 (weighted 2-D Kabsch); empty when the
/// weights vanish.
std::optional<Pose2> weightedFit(const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source,
                                 const std::vector<int>& subset, const std::vector<double>& weights) {
  double total = 0.0;
  Eigen::Vector2d mean_t = Eigen::Vector2d::Zero(), mean_s = Eigen::Vector2d::Zero();
  for (size_t k = 0; k < subset.size(); ++k) {
    const auto i = static_cast<size_t>(subset[k]);
    total += weights[k];
    mean_t += weights[k] * target[i];
    mean_s += weights[k] * source[i];
  }
  if (!(total > 0.0)) return std::nullopt;
  mean_t /= total;
  mean_s /= total;
  double dot = 0.0, cross = 0.0;
  for (size_t k = 0; k < subset.size(); ++k) {
    const auto i = static_cast<size_t>(subset[k]);
    const Eigen::Vector2d a = source[i] - mean_s, b = target[i] - mean_t;
    dot += weights[k] * a.dot(b);
    cross += weights[k] * (a.x() * b.y() - a.y() * b.x());
  }
  const double theta = std::atan2(cross, dot);
  const Eigen::Vector2d t = mean_t - Eigen::Rotation2Dd(theta) * mean_s;
  return Pose2(t.x(), t.y(), theta);
}

/// Paper eq. 6 under the robust loss, by iteratively reweighted least squares from `initial`: each step weights
/// the matches by rho' at the current transform and solves the weighted fit exactly. Its fixed point is the
/// stationary point a Gauss-Newton or Levenberg-Marquardt solver reaches on the robustified problem.
/// Returns the transform and the robustified information matrix sum rho'_i J_i^T J_i (x, y, theta) there.
std::optional<std::pair<Pose2, Eigen::Matrix3d>> robustFit(const std::vector<Eigen::Vector2d>& target,
                                                           const std::vector<Eigen::Vector2d>& source,
                                                           const std::vector<int>& subset, const Pose2& initial,
                                                           const FitSettings& settings) {
  constexpr int kMaxIterations = 100;
  constexpr double kConvergedM = 1e-12, kConvergedRad = 1e-12;
  Pose2 T = initial;
  std::vector<double> weights(subset.size());
  const auto weigh = [&](const Pose2& at) {
    const Eigen::Matrix2d R = at.rotation();
    const Eigen::Vector2d t = at.translation();
    for (size_t k = 0; k < subset.size(); ++k) {
      const auto i = static_cast<size_t>(subset[k]);
      weights[k] = lossWeight(settings.loss, settings.loss_scale_m, (R * source[i] + t - target[i]).squaredNorm());
    }
  };
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    weigh(T);
    const std::optional<Pose2> next = weightedFit(target, source, subset, weights);
    if (!next) return std::nullopt;
    const bool converged = (next->translation() - T.translation()).norm() < kConvergedM &&
                           std::abs(wrapAngle(next->theta - T.theta)) < kConvergedRad;
    T = *next;
    if (converged) break;
  }
  weigh(T);
  // r_i = R s_i + t - q_i: dr/dt = I, dr/dtheta = R' s_i.
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  const double c = std::cos(T.theta), s = std::sin(T.theta);
  for (size_t k = 0; k < subset.size(); ++k) {
    const Eigen::Vector2d& p = source[static_cast<size_t>(subset[k])];
    Eigen::Matrix<double, 2, 3> J;
    J << 1.0, 0.0, -s * p.x() - c * p.y(), 0.0, 1.0, c * p.x() - s * p.y();
    information += weights[k] * J.transpose() * J;
  }
  if (!information.allFinite()) return std::nullopt;
  return std::make_pair(T, information);
}

std::vector<int> inliersOf(const Pose2& T, const std::vector<Eigen::Vector2d>& target,
                           const std::vector<Eigen::Vector2d>& source, double threshold) {
  std::vector<int> inliers;
  const double t2 = threshold * threshold;
  const Eigen::Matrix2d R = T.rotation();  // once, not per point
  const Eigen::Vector2d t = T.translation();
  for (size_t i = 0; i < target.size(); ++i) {
    if ((R * source[i] + t - target[i]).squaredNorm() <= t2) inliers.push_back(static_cast<int>(i));
  }
  return inliers;
}

/// How many matches `T` maps within `threshold` (inliersOf's size, without building the list); with
/// min_motion > 0, only among the matches whose two points lie farther apart than that (moved in the image).
int supportOf(const Pose2& T, const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source,
              double threshold, double min_motion = 0.0) {
  int support = 0;
  const double t2 = threshold * threshold, m2 = min_motion * min_motion;
  const Eigen::Matrix2d R = T.rotation();
  const Eigen::Vector2d t = T.translation();
  for (size_t i = 0; i < target.size(); ++i) {
    if (min_motion > 0.0 && (source[i] - target[i]).squaredNorm() <= m2) continue;
    support += (R * source[i] + t - target[i]).squaredNorm() <= t2 ? 1 : 0;
  }
  return support;
}

/// Closed-form least-squares rigid fit (2-D Kabsch); always a proper rotation.
Pose2 leastSquaresFit(const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source,
                      const std::vector<int>& subset) {
  Eigen::Vector2d mean_t = Eigen::Vector2d::Zero(), mean_s = Eigen::Vector2d::Zero();
  for (int i : subset) mean_t += target[static_cast<size_t>(i)], mean_s += source[static_cast<size_t>(i)];
  mean_t /= static_cast<double>(subset.size());
  mean_s /= static_cast<double>(subset.size());
  double dot = 0.0, cross = 0.0;
  for (int i : subset) {
    const Eigen::Vector2d a = source[static_cast<size_t>(i)] - mean_s, b = target[static_cast<size_t>(i)] - mean_t;
    dot += a.dot(b);
    cross += a.x() * b.y() - a.y() * b.x();
  }
  const double theta = std::atan2(cross, dot);
  const Eigen::Vector2d t = mean_t - Eigen::Rotation2Dd(theta) * mean_s;
  return Pose2(t.x(), t.y(), theta);
}

struct Hypothesis {
  Pose2 T;
  int support = 0;
};

struct RansacResult {
  std::vector<int> inliers;  ///< of the best hypothesis
  Pose2 best;
  int rival_support = 0;     ///< the best hypothesis far from `best`
  std::vector<Pose2> rivals;  ///< distinct strong hypotheses far from `best`, strongest first
};

/// True when two transforms are different explanations, not the same one seen through noise.
bool farApart(const Pose2& a, const Pose2& b, const FitSettings& settings) {
  const double rotation = std::abs(wrapAngle(a.theta - b.theta));
  if (settings.rival_max_rotation_rad) {
    // Only shifted copies count: a repetition of the floor, not the best pose turned about a matched point.
    return rotation <= *settings.rival_max_rotation_rad && (a.translation() - b.translation()).norm() > 0.01;
  }
  return (a.translation() - b.translation()).norm() > 0.01 || rotation > 3.0 * M_PI / 180.0;
}

/// 2-point RANSAC: the hypothesis with the most inliers. Stops early once the inlier ratio makes a
/// better one unlikely (99.9% confidence), unless every hypothesis is wanted to measure ambiguity.
bool withinPrior(const Pose2& T, const std::optional<TransformPrior>& prior) {
  if (!prior) return true;
  const Pose2 difference = prior->T_target_source.inverse() * T;
  return difference.translation().norm() <= prior->radius_m && std::abs(difference.theta) <= prior->radius_rad;
}

RansacResult ransac(const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source,
                    const FitSettings& settings, const std::optional<TransformPrior>& prior) {
  std::mt19937 rng(static_cast<std::mt19937::result_type>(settings.seed));
  std::uniform_int_distribution<size_t> pick(0, target.size() - 1);
  const double thr = settings.ransac_inlier_m;
  RansacResult result;
  std::vector<Hypothesis> tried;
  int needed = settings.ransac_iterations;
  for (int it = 0; it < needed; ++it) {
    const size_t i = pick(rng), j = pick(rng);
    const Eigen::Vector2d ds = source[j] - source[i], dt = target[j] - target[i];
    // Too short a baseline fixes no rotation; unequal lengths cannot both be inliers of a rigid motion.
    if (ds.norm() < 4.0 * thr || std::abs(ds.norm() - dt.norm()) > 2.0 * thr) continue;
    const double theta = std::atan2(ds.x() * dt.y() - ds.y() * dt.x(), ds.dot(dt));
    const Eigen::Vector2d t = 0.5 * (target[i] + target[j]) - Eigen::Rotation2Dd(theta) * (0.5 * (source[i] + source[j]));
    const Pose2 T(t.x(), t.y(), theta);
    if (!withinPrior(T, prior)) continue;
    const int support = supportOf(T, target, source, thr);  // the list only for a new best
    if (settings.measure_ambiguity) tried.push_back({T, support});
    if (support <= static_cast<int>(result.inliers.size())) continue;
    result.inliers = inliersOf(T, target, source, thr);
    result.best = T;
    if (settings.measure_ambiguity) continue;
    const double w = static_cast<double>(result.inliers.size()) / static_cast<double>(target.size());
    const double miss = std::max(1e-12, 1.0 - w * w);
    needed = std::min(settings.ransac_iterations, static_cast<int>(std::ceil(std::log(1e-3) / std::log(miss))) + 1);
  }
  // Strongest first: once a hypothesis's whole support cannot beat the rival found, none after it can.
  std::sort(tried.begin(), tried.end(), [](const Hypothesis& a, const Hypothesis& b) { return a.support > b.support; });
  // The list of rivals goes on while they are strong (a third of the best's support) and distinct; the
  // rival support is the same as if it stopped at the first that cannot beat the one found.
  const int strong = static_cast<int>(result.inliers.size()) / 3;
  for (const Hypothesis& h : tried) {
    const bool listing = result.rivals.size() < RigidEstimate::kMaxRivals && h.support >= strong;
    if (h.support <= result.rival_support && !listing) break;
    if (!farApart(h.T, result.best, settings)) continue;
    const int support = settings.rival_min_motion_m > 0.0 ? supportOf(h.T, target, source, thr, settings.rival_min_motion_m) : h.support;
    result.rival_support = std::max(result.rival_support, support);
    const bool distinct = std::none_of(result.rivals.begin(), result.rivals.end(), [&](const Pose2& r) { return !farApart(h.T, r, settings); });
    if (listing && distinct && support >= strong) result.rivals.push_back(h.T);
  }
  return result;
}

/// True when the points lie (nearly) on a line: the fit's rotation would hang on one direction.
bool isDegenerate(const std::vector<Eigen::Vector2d>& points, const std::vector<int>& subset, double min_spread_m) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int i : subset) mean += points[static_cast<size_t>(i)];
  mean /= static_cast<double>(subset.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (int i : subset) {
    const Eigen::Vector2d d = points[static_cast<size_t>(i)] - mean;
    scatter += d * d.transpose();
  }
  scatter /= static_cast<double>(subset.size());
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(scatter).eigenvalues()(0);
  return std::sqrt(std::max(0.0, smallest)) < min_spread_m;
}

}  // namespace

bool tooLittleEvidence(FitStatus status) {
  return status == FitStatus::too_few_matches || status == FitStatus::too_few_inliers || status == FitStatus::degenerate;
}

const char* fitStatusName(FitStatus status) {
  switch (status) {
    case FitStatus::ok: return "ok";
    case FitStatus::too_few_matches: return "too_few_matches";
    case FitStatus::too_few_inliers: return "too_few_inliers";
    case FitStatus::degenerate: return "degenerate";
    case FitStatus::solver_failed: return "solver_failed";
    case FitStatus::ambiguous: return "ambiguous";
    case FitStatus::implausible_motion: return "implausible_motion";
    case FitStatus::still: return "still";
  }
  return "unknown";
}

double RigidEstimate::covarianceScore() const {
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvalues()(2);
  return std::log10(std::max(largest, 1e-300));
}

RigidEstimate fitRigidTransform(const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source,
                                const FitSettings& settings, const std::optional<TransformPrior>& prior) {
  RigidEstimate estimate;
  const size_t min_inliers = static_cast<size_t>(std::max(3, settings.min_inliers));
  if (target.size() != source.size() || target.size() < min_inliers) return estimate;  // too_few_matches

  const RansacResult consensus = ransac(target, source, settings, prior);
  std::vector<int> inliers = consensus.inliers;
  estimate.inliers = static_cast<int>(inliers.size());
  estimate.rival_inliers = consensus.rival_support;
  estimate.rivals = consensus.rivals;
  if (inliers.size() < min_inliers) {
    estimate.status = FitStatus::too_few_inliers;
    return estimate;
  }
  if (isDegenerate(source, inliers, settings.min_spread_inliers * settings.ransac_inlier_m)) {
    estimate.status = FitStatus::degenerate;
    return estimate;
  }
  // Robust refinement over every match near the consensus, starting from its least-squares fit.
  RigidEstimate refined = refineRigidTransform(target, source, leastSquaresFit(target, source, inliers), settings);
  refined.rival_inliers = estimate.rival_inliers;
  refined.rivals = estimate.rivals;
  return refined;
}

RigidEstimate refineRigidTransform(const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source,
                                   const Pose2& initial, const FitSettings& settings) {
  RigidEstimate estimate;
  const size_t min_inliers = static_cast<size_t>(std::max(3, settings.min_inliers));
  if (target.size() != source.size() || target.size() < min_inliers) return estimate;  // too_few_matches
  const std::vector<int> refine_set = inliersOf(initial, target, source, 3.0 * settings.ransac_inlier_m);
  if (refine_set.size() < min_inliers) {
    estimate.status = FitStatus::too_few_inliers;
    estimate.inliers = static_cast<int>(refine_set.size());
    return estimate;
  }
  if (isDegenerate(source, refine_set, settings.min_spread_inliers * settings.ransac_inlier_m)) {
    estimate.status = FitStatus::degenerate;
    return estimate;
  }
  const auto solution = robustFit(target, source, refine_set, initial, settings);
  const Eigen::LLT<Eigen::Matrix3d> cholesky(solution ? solution->second : Eigen::Matrix3d::Zero());
  if (!solution || cholesky.info() != Eigen::Success) {
    estimate.status = FitStatus::solver_failed;
    return estimate;
  }
  const Eigen::Matrix3d unit_covariance = cholesky.solve(Eigen::Matrix3d::Identity());
  estimate.T_target_source = solution->first;

  // The information assumes unit residual variance; scale by the fit's own residual variance.
  const std::vector<int> inliers = inliersOf(estimate.T_target_source, target, source, settings.ransac_inlier_m);
  double sum_squares = 0.0;
  for (int i : inliers) {
    sum_squares += (estimate.T_target_source * source[static_cast<size_t>(i)] - target[static_cast<size_t>(i)]).squaredNorm();
  }
  const double dof = std::max(1.0, 2.0 * static_cast<double>(inliers.size()) - 3.0);
  estimate.inliers = static_cast<int>(inliers.size());
  estimate.rms_residual_m = std::sqrt(sum_squares / static_cast<double>(std::max<size_t>(1, inliers.size())));
  estimate.covariance = unit_covariance * (sum_squares / dof);
  estimate.status = inliers.size() < min_inliers ? FitStatus::too_few_inliers : FitStatus::ok;
  return estimate;
}

Pose2 leastSquaresRigid(const std::vector<Eigen::Vector2d>& target, const std::vector<Eigen::Vector2d>& source) {
  const size_t n = std::min(target.size(), source.size());
  if (n == 0) return Pose2();
  std::vector<int> all(n);
  for (size_t i = 0; i < n; ++i) all[i] = static_cast<int>(i);
  return leastSquaresFit(target, source, all);
}

bool withinAtSigmas(const Eigen::Matrix3d& covariance, double sigmas, double within_m, double within_rad) {
  const double sigma_rad = std::sqrt(std::max(0.0, covariance(2, 2)));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> position(covariance.topLeftCorner<2, 2>());
  const double sigma_m = std::sqrt(std::max(0.0, position.eigenvalues().maxCoeff()));
  return sigmas * sigma_rad <= within_rad && sigmas * sigma_m <= within_m;
}

bool showsARepetition(const RigidEstimate& fit, int min_inliers) {
  return !fit.rivals.empty() && fit.rival_inliers >= min_inliers;
}

}  // namespace groundslam
