#include "groundslam/core/MountEstimation.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <utility>
#include <vector>

#include <Eigen/Cholesky>

#include "groundslam/core/MountPairCost.hpp"

namespace groundslam {
namespace {

Eigen::Matrix3d roll_pitch(double roll, double pitch) {
  return (Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY())).toRotationMatrix();
}

}  // namespace

Eigen::Isometry3d mountFor(const Eigen::Isometry3d& calibrated, const MountState& state) {
  Eigen::Isometry3d T = calibrated;
  T.linear() = roll_pitch(state.roll_rad, state.pitch_rad) * calibrated.linear();
  T.translation().z() = state.height_m;
  return T;
}

MountState calibratedState(const Eigen::Isometry3d& calibrated) { return {0.0, 0.0, calibrated.translation().z()}; }

MountEstimate estimateMount(const std::vector<Eigen::Vector2d>& reference_rays, const std::vector<Eigen::Vector2d>& current_rays,
                            const Eigen::Isometry3d& calibrated, const MountState& reference, const Pose2& T_guess,
                            const MountEstimationSettings& settings) {
  return estimateMount({MountObservation{reference_rays, current_rays, reference, T_guess}}, calibrated, settings);
}

namespace {

constexpr double kHuberScale = 3.0;  // pair residuals beyond three sigma are down-weighted

/// The least-squares problem of estimateMount: parameters x = the current state (roll, pitch, height), then
/// per observation with pairs the reference's roll and pitch (its height is held: it fixes the scale) and the
/// motion (x, y, theta). Cost = 1/2 sum rho(|r|^2) over the pairs (Huber) plus 1/2 |prior|^2 of each prior.
class MountProblem {
 public:
  struct Slot {
    double reference_height = 0.0;
    Eigen::Vector2d reference_mean;  ///< the reference's believed roll and pitch
  };

  MountProblem(const MountEstimationSettings& settings, const MountState& nominal) : settings_(settings) {
    current_mean_ << nominal.roll_rad, nominal.pitch_rad, nominal.height_m;
    current_sigma_ << settings.tilt_prior_rad, settings.tilt_prior_rad, settings.height_prior_m;
  }
  int addSlot(const Slot& slot) {
    slots_.push_back(slot);
    return static_cast<int>(slots_.size()) - 1;
  }
  void addPair(int slot, const MountPairCost& pair) { pairs_.push_back({slot, pair}); }
  int parameters() const { return 3 + 5 * slots(); }
  int slots() const { return static_cast<int>(slots_.size()); }
  size_t pairs() const { return pairs_.size(); }

  /// The cost at x; with `information` and `gradient`, also sum w J^T J and sum w J^T r (w = rho', the Huber
  /// weight, as Ceres robustifies a residual whose loss has no positive curvature).
  double evaluate(const Eigen::VectorXd& x, Eigen::MatrixXd* information, Eigen::VectorXd* gradient) const {
    const int n = parameters();
    if (information) {
      information->setZero(n, n);
      gradient->setZero(n);
    }
    const MountAngles current(x.data());
    std::vector<MountAngles> references;
    std::vector<Eigen::Vector2d> motion_cs;
    for (size_t j = 0; j < slots_.size(); ++j) {
      const int at = 3 + 5 * static_cast<int>(j);
      const double state[3] = {x[at], x[at + 1], slots_[j].reference_height};
      references.emplace_back(state);
      motion_cs.emplace_back(std::cos(x[at + 4]), std::sin(x[at + 4]));
    }
    double cost = 0.0;
    Eigen::Matrix<double, 2, 3> d_reference, d_current, d_motion;
    Eigen::Matrix<double, 2, 8> J;  // columns: current (3), reference roll and pitch (2), motion (3)
    for (const auto& [slot, pair] : pairs_) {
      const int at = 3 + 5 * slot;
      const bool want = information != nullptr;
      const Eigen::Vector2d r = pair.evaluate(references[static_cast<size_t>(slot)], current, x.data() + at + 2,
                                              motion_cs[static_cast<size_t>(slot)].x(), motion_cs[static_cast<size_t>(slot)].y(),
                                              want ? &d_reference : nullptr, want ? &d_current : nullptr, want ? &d_motion : nullptr);
      const double s = r.squaredNorm(), a2 = kHuberScale * kHuberScale;
      const double rho = s <= a2 ? s : 2.0 * kHuberScale * std::sqrt(s) - a2;
      cost += 0.5 * rho;
      if (!want) continue;
      const double w = s <= a2 ? 1.0 : kHuberScale / std::sqrt(s);
      J << d_current, d_reference.leftCols<2>(), d_motion;
      const Eigen::Matrix<double, 8, 8> JtJ = w * J.transpose() * J;
      const Eigen::Matrix<double, 8, 1> Jtr = w * J.transpose() * r;
      const int index[8] = {0, 1, 2, at, at + 1, at + 2, at + 3, at + 4};
      for (int a = 0; a < 8; ++a) {
        (*gradient)[index[a]] += Jtr[a];
        for (int b = 0; b < 8; ++b) (*information)(index[a], index[b]) += JtJ(a, b);
      }
    }
    // The priors: the current state around the calibrated mount, each reference's tilt around its belief.
    const Eigen::Vector3d current_r = (x.head<3>() - current_mean_).cwiseQuotient(current_sigma_);
    cost += 0.5 * current_r.squaredNorm();
    if (information) {
      for (int i = 0; i < 3; ++i) {
        (*information)(i, i) += 1.0 / (current_sigma_[i] * current_sigma_[i]);
        (*gradient)[i] += current_r[i] / current_sigma_[i];
      }
    }
    for (size_t j = 0; j < slots_.size(); ++j) {
      const int at = 3 + 5 * static_cast<int>(j);
      const Eigen::Vector2d prior_r = (x.segment<2>(at) - slots_[j].reference_mean) / settings_.reference_sigma_rad;
      cost += 0.5 * prior_r.squaredNorm();
      if (!information) continue;
      for (int i = 0; i < 2; ++i) {
        (*information)(at + i, at + i) += 1.0 / (settings_.reference_sigma_rad * settings_.reference_sigma_rad);
        (*gradient)[at + i] += prior_r[i] / settings_.reference_sigma_rad;
      }
    }
    return cost;
  }

  /// Levenberg-Marquardt from x (at most `max_iterations` steps tried); false when the cost is not finite.
  bool solve(Eigen::VectorXd& x, int max_iterations, double& final_cost) const {
    Eigen::MatrixXd H;
    Eigen::VectorXd g;
    double cost = evaluate(x, &H, &g);
    if (!std::isfinite(cost)) return false;
    double lambda = 1e-4;
    for (int iteration = 0; iteration < max_iterations; ++iteration) {
      Eigen::MatrixXd damped = H;
      damped.diagonal() += lambda * H.diagonal().cwiseMax(1e-6);
      const Eigen::LDLT<Eigen::MatrixXd> solver(damped);
      const Eigen::VectorXd step = solver.solve(-g);
      if (solver.info() != Eigen::Success || !step.allFinite()) return false;
      const Eigen::VectorXd candidate = x + step;
      const double candidate_cost = evaluate(candidate, nullptr, nullptr);
      if (std::isfinite(candidate_cost) && candidate_cost < cost) {
        const double decrease = (cost - candidate_cost) / std::max(cost, 1e-300);
        x = candidate;
        cost = evaluate(x, &H, &g);
        lambda = std::max(lambda / 3.0, 1e-12);
        if (decrease < 1e-10 || step.norm() < 1e-12 * (x.norm() + 1e-12)) break;
      } else {
        lambda *= 4.0;
        if (lambda > 1e16) break;
      }
    }
    final_cost = cost;
    return true;
  }

  /// The data's part of the problem at x with every state free, the references' heights too (see MountFactor):
  /// the motions marginalised out (Schur complement), scaled to the residuals' variance.
  MountFactor factorAt(const Eigen::VectorXd& x, double residual_variance) const {
    // Parameters: the current state (3), then per slot the reference's state (3) and the motion (3).
    const int n = 3 + 6 * slots();
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(n), linearisation(3 + 3 * slots());
    const MountAngles current(x.data());
    linearisation.head<3>() = x.head<3>();
    std::vector<MountAngles> references;
    for (size_t j = 0; j < slots_.size(); ++j) {
      const int at = 3 + 5 * static_cast<int>(j);
      const double state[3] = {x[at], x[at + 1], slots_[j].reference_height};
      references.emplace_back(state);
      linearisation.segment<3>(3 + 3 * static_cast<Eigen::Index>(j)) << x[at], x[at + 1], slots_[j].reference_height;
    }
    Eigen::Matrix<double, 2, 3> d_reference, d_current, d_motion;
    Eigen::Matrix<double, 2, 9> J;
    for (const auto& [slot, pair] : pairs_) {
      const int at = 3 + 5 * slot;
      const double theta = x[at + 4];
      const Eigen::Vector2d r = pair.evaluate(references[static_cast<size_t>(slot)], current, x.data() + at + 2, std::cos(theta),
                                              std::sin(theta), &d_reference, &d_current, &d_motion);
      const double s = r.squaredNorm();
      const double w = s <= kHuberScale * kHuberScale ? 1.0 : kHuberScale / std::sqrt(s);
      J << d_current, d_reference, d_motion;
      const int base = 3 + 6 * slot;
      const int index[9] = {0, 1, 2, base, base + 1, base + 2, base + 3, base + 4, base + 5};
      const Eigen::Matrix<double, 9, 9> JtJ = w * J.transpose() * J;
      const Eigen::Matrix<double, 9, 1> Jtr = w * J.transpose() * r;
      for (int a = 0; a < 9; ++a) {
        g[index[a]] += Jtr[a];
        for (int b = 0; b < 9; ++b) H(index[a], index[b]) += JtJ(a, b);
      }
    }
    std::vector<int> kept = {0, 1, 2}, marginalised;
    for (int j = 0; j < slots(); ++j) {
      kept.insert(kept.end(), {3 + 6 * j, 4 + 6 * j, 5 + 6 * j});
      marginalised.insert(marginalised.end(), {6 + 6 * j, 7 + 6 * j, 8 + 6 * j});
    }
    MountFactor factor;
    const auto k = static_cast<Eigen::Index>(kept.size()), m = static_cast<Eigen::Index>(marginalised.size());
    Eigen::MatrixXd Hkk(k, k), Hkm(k, m), Hmm(m, m);
    Eigen::VectorXd gk(k), gm(m);
    for (Eigen::Index a = 0; a < k; ++a) {
      gk[a] = g[kept[static_cast<size_t>(a)]];
      for (Eigen::Index b = 0; b < k; ++b) Hkk(a, b) = H(kept[static_cast<size_t>(a)], kept[static_cast<size_t>(b)]);
      for (Eigen::Index b = 0; b < m; ++b) Hkm(a, b) = H(kept[static_cast<size_t>(a)], marginalised[static_cast<size_t>(b)]);
    }
    for (Eigen::Index a = 0; a < m; ++a) {
      gm[a] = g[marginalised[static_cast<size_t>(a)]];
      for (Eigen::Index b = 0; b < m; ++b) Hmm(a, b) = H(marginalised[static_cast<size_t>(a)], marginalised[static_cast<size_t>(b)]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> solver(Hmm);
    if (solver.info() != Eigen::Success) return factor;
    const Eigen::MatrixXd HkmHmmInv = solver.solve(Hkm.transpose()).transpose();
    if (!HkmHmmInv.allFinite()) return factor;
    // The residuals are ground distances, which shrink with a common scale of every height (and of the motion):
    // left in, that direction would pull all heights toward zero. Two views say nothing about it; it is
    // projected out, and the prior alone keeps the heights' level.
    Eigen::VectorXd scale = Eigen::VectorXd::Zero(k);
    for (Eigen::Index a = 2; a < k; a += 3) scale[a] = linearisation[a];
    scale.normalize();
    const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(k, k) - scale * scale.transpose();
    factor.information = P * (Hkk - HkmHmmInv * Hkm.transpose()) * P / residual_variance;
    factor.gradient = P * (gk - HkmHmmInv * gm) / residual_variance;
    factor.linearisation = linearisation;
    return factor;
  }

 private:
  const MountEstimationSettings& settings_;
  Eigen::Vector3d current_mean_, current_sigma_;
  std::vector<Slot> slots_;
  std::vector<std::pair<int, MountPairCost>> pairs_;
};

}  // namespace

MountEstimate estimateMount(const std::vector<MountObservation>& observations, const Eigen::Isometry3d& calibrated,
                            const MountEstimationSettings& settings) {
  MountEstimate estimate;
  size_t total = 0;
  for (const MountObservation& o : observations) total += std::min(o.reference_rays.size(), o.current_rays.size());
  if (observations.empty() || total < static_cast<size_t>(std::max(3, settings.min_pairs))) return estimate;
  const Eigen::Matrix3d R0 = calibrated.linear();
  const Eigen::Vector2d centre_xy = calibrated.translation().head<2>();
  MountProblem problem(settings, calibratedState(calibrated));
  const MountState& first = observations.front().reference;
  std::vector<double> x = {first.roll_rad, first.pitch_rad, first.height_m};
  std::vector<int> slot_of(observations.size(), -1);  // an observation without pairs adds no parameters
  for (size_t k = 0; k < observations.size(); ++k) {
    const MountObservation& o = observations[k];
    const size_t n = std::min(o.reference_rays.size(), o.current_rays.size());
    if (n == 0) continue;
    slot_of[k] = problem.addSlot({o.reference.height_m, Eigen::Vector2d(o.reference.roll_rad, o.reference.pitch_rad)});
    x.insert(x.end(), {o.reference.roll_rad, o.reference.pitch_rad, o.T_guess.x, o.T_guess.y, o.T_guess.theta});
    const size_t step = std::max<size_t>(1, n / static_cast<size_t>(std::max(1, settings.max_pairs)));
    const double sigma_m = o.point_sigma_m > 0.0 ? o.point_sigma_m : settings.point_sigma_m;
    for (size_t i = 0; i < n; i += step) {
      const Eigen::Vector3d ref = R0 * Eigen::Vector3d(o.reference_rays[i].x(), o.reference_rays[i].y(), 1.0);
      const Eigen::Vector3d cur = R0 * Eigen::Vector3d(o.current_rays[i].x(), o.current_rays[i].y(), 1.0);
      problem.addPair(slot_of[k], MountPairCost(ref, cur, centre_xy, sigma_m));
    }
  }
  estimate.pairs = static_cast<int>(problem.pairs());
  Eigen::VectorXd solution = Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size()));
  double final_cost = 0.0;
  if (!problem.solve(solution, 20, final_cost) || !solution.allFinite() || solution[2] <= 0.0) return estimate;
  // The covariance of the current state from the normal equations at the solution.
  Eigen::MatrixXd information;
  Eigen::VectorXd gradient;
  problem.evaluate(solution, &information, &gradient);
  const Eigen::LLT<Eigen::MatrixXd> cholesky(information);
  if (cholesky.info() != Eigen::Success) return estimate;
  const Eigen::MatrixXd covariance = cholesky.solve(Eigen::MatrixXd::Identity(information.rows(), information.cols()));
  if (!covariance.allFinite()) return estimate;
  const Eigen::Matrix3d state_covariance = covariance.topLeftCorner<3, 3>();
  // The information assumes residuals of unit variance; scale by their observed variance (degrees of freedom:
  // two per pair, less the current state and a full state and motion per reference).
  const double dof = std::max(1.0, 2.0 * estimate.pairs - (3.0 + 6.0 * problem.slots()));
  const double residual_variance = std::max(1.0, 2.0 * final_cost / dof);
  estimate.tilt_covariance = state_covariance.topLeftCorner<2, 2>() * residual_variance;
  estimate.height_variance = state_covariance(2, 2) * residual_variance;
  estimate.factor = problem.factorAt(solution, residual_variance);
  for (size_t k = 0; k < observations.size(); ++k) {
    if (slot_of[k] >= 0) estimate.factor.observations.push_back(static_cast<int>(k));
  }
  estimate.ok = true;
  estimate.current = {solution[0], solution[1], solution[2]};
  const MountObservation& o = observations.front();
  if (slot_of[0] >= 0) {
    const int at = 3 + 5 * slot_of[0];
    estimate.reference = {solution[at], solution[at + 1], o.reference.height_m};
    estimate.T_reference_current = Pose2(solution[at + 2], solution[at + 3], solution[at + 4]);
  } else {
    estimate.reference = o.reference;
    estimate.T_reference_current = o.T_guess;
  }
  return estimate;
}

}  // namespace groundslam
