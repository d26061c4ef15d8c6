#include "groundslam/core/RigidFit.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include <Eigen/Eigenvalues>
#include <ceres/ceres.h>

#include "groundslam/core/NormalCovariance.hpp"

namespace groundslam {
namespace {

/// Geman-McClure, rho(s) = s d^2 / (s + d^2) for s = r^2: bounded, so gross outliers have no pull.
class GemanMcClureLoss : public ceres::LossFunction {
 public:
  explicit GemanMcClureLoss(double scale) : d2_(scale * scale) {}
  void Evaluate(double s, double rho[3]) const override {
    const double denom = s + d2_;
    rho[0] = s * d2_ / denom;
    rho[1] = d2_ * d2_ / (denom * denom);
    rho[2] = -2.0 * d2_ * d2_ / (denom * denom * denom);
  }

 private:
  double d2_;
};

ceres::LossFunction* makeLoss(RobustLoss loss, double scale) {
  switch (loss) {
    case RobustLoss::huber: return new ceres::HuberLoss(scale);
    case RobustLoss::cauchy: return new ceres::CauchyLoss(scale);
    case RobustLoss::geman_mcclure: return new GemanMcClureLoss(scale);
  }
  throw std::invalid_argument("odometry.loss: unknown robust loss " + std::to_string(static_cast<int>(loss)));
}

/// r = R(theta) p_source + t - p_target, the 2-D misfit of one match (paper eq. 6).
struct PointResidual {
  PointResidual(const Eigen::Vector2d& target, const Eigen::Vector2d& source) : target_(target), source_(source) {}
  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    const T c = ceres::cos(pose[2]), s = ceres::sin(pose[2]);
    residual[0] = c * source_.x() - s * source_.y() + pose[0] - target_.x();
    residual[1] = s * source_.x() + c * source_.y() + pose[1] - target_.y();
    return true;
  }
  Eigen::Vector2d target_, source_;
};

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
    std::vector<int> inliers = inliersOf(T, target, source, thr);
    if (settings.measure_ambiguity) tried.push_back({T, static_cast<int>(inliers.size())});
    if (inliers.size() <= result.inliers.size()) continue;
    result.inliers = std::move(inliers);
    result.best = T;
    if (settings.measure_ambiguity) continue;
    const double w = static_cast<double>(result.inliers.size()) / static_cast<double>(target.size());
    const double miss = std::max(1e-12, 1.0 - w * w);
    needed = std::min(settings.ransac_iterations, static_cast<int>(std::ceil(std::log(1e-3) / std::log(miss))) + 1);
  }
  for (const Hypothesis& h : tried) {
    if (farApart(h.T, result.best, settings)) result.rival_support = std::max(result.rival_support, h.support);
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

const char* fitStatusName(FitStatus status) {
  switch (status) {
    case FitStatus::ok: return "ok";
    case FitStatus::too_few_matches: return "too_few_matches";
    case FitStatus::too_few_inliers: return "too_few_inliers";
    case FitStatus::degenerate: return "degenerate";
    case FitStatus::solver_failed: return "solver_failed";
    case FitStatus::ambiguous: return "ambiguous";
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
  if (inliers.size() < min_inliers) {
    estimate.status = FitStatus::too_few_inliers;
    return estimate;
  }
  if (isDegenerate(source, inliers, 2.0 * settings.ransac_inlier_m)) {
    estimate.status = FitStatus::degenerate;
    return estimate;
  }
  // Robust refinement over every match near the consensus, starting from its least-squares fit.
  RigidEstimate refined = refineRigidTransform(target, source, leastSquaresFit(target, source, inliers), settings);
  refined.rival_inliers = estimate.rival_inliers;
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
  if (isDegenerate(source, refine_set, 2.0 * settings.ransac_inlier_m)) {
    estimate.status = FitStatus::degenerate;
    return estimate;
  }
  double pose[3] = {initial.x, initial.y, initial.theta};
  ceres::Problem problem;
  ceres::LossFunction* loss = makeLoss(settings.loss, settings.loss_scale_m);  // shared, owned by the problem
  for (int i : refine_set) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PointResidual, 2, 3>(
                                 new PointResidual(target[static_cast<size_t>(i)], source[static_cast<size_t>(i)])),
                             loss, pose);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;  // three parameters: the normal equations are 3x3
  options.max_num_iterations = 25;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  const std::optional<Eigen::MatrixXd> unit_covariance =
      summary.IsSolutionUsable() ? normalCovariance(problem, {pose}) : std::nullopt;
  if (!unit_covariance) {
    estimate.status = FitStatus::solver_failed;
    return estimate;
  }
  estimate.T_target_source = Pose2(pose[0], pose[1], pose[2]);

  // Ceres assumes unit residual variance; scale by the fit's own residual variance.
  const std::vector<int> inliers = inliersOf(estimate.T_target_source, target, source, settings.ransac_inlier_m);
  double sum_squares = 0.0;
  for (int i : inliers) {
    sum_squares += (estimate.T_target_source * source[static_cast<size_t>(i)] - target[static_cast<size_t>(i)]).squaredNorm();
  }
  const double dof = std::max(1.0, 2.0 * static_cast<double>(inliers.size()) - 3.0);
  estimate.inliers = static_cast<int>(inliers.size());
  estimate.rms_residual_m = std::sqrt(sum_squares / static_cast<double>(std::max<size_t>(1, inliers.size())));
  estimate.covariance = *unit_covariance * (sum_squares / dof);
  estimate.status = inliers.size() < min_inliers ? FitStatus::too_few_inliers : FitStatus::ok;
  return estimate;
}

}  // namespace groundslam
