#include "groundslam/core/MountSmoother.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

namespace groundslam {
namespace {

constexpr int kState = 3;  // roll, pitch, height
constexpr double kCorrelations[] = {0.0, 0.5, 0.8, 0.9, 0.95, 0.98};
constexpr double kMaxSteps = 1000.0;  // 0.98^1000: the frames are independent
constexpr int kRobustIterations = 5;

bool usable(const FrameMountFactor& f) {
  const auto size = static_cast<Eigen::Index>(kState * f.frames.size());
  const MountFactor& t = f.factor;
  return !f.frames.empty() && t.information.rows() == size && t.information.cols() == size && t.gradient.size() == size &&
         t.linearisation.size() == size && t.information.allFinite() && t.gradient.allFinite() && t.linearisation.allFinite();
}

/// Every frame the factor ties lies within first .. first+count-1.
bool tiesFramesWithin(const FrameMountFactor& f, int first, int count) {
  return std::all_of(f.frames.begin(), f.frames.end(), [&](int frame) { return frame >= first && frame < first + count; });
}

/// The factors over frames first .. first+count-1 in departures d from the nominal state: their summed cost is
/// 1/2 d^T H d - eta^T d + const.
struct NormalEquations {
  int first = 0, count = 0;
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd eta;
};

NormalEquations normalEquations(int first, int count, const std::vector<FrameMountFactor>& factors, const Eigen::Vector3d& nominal,
                                bool choosing_priors, const std::vector<double>& weights = {}) {
  NormalEquations system;
  system.first = first;
  system.count = count;
  system.eta = Eigen::VectorXd::Zero(kState * static_cast<Eigen::Index>(count));
  for (size_t k = 0; k < factors.size(); ++k) {
    const FrameMountFactor& f = factors[k];
    const double w = k < weights.size() ? weights[k] : 1.0;
    if (!usable(f) || (choosing_priors && !f.chooses_priors) || !(w > 0.0) || !tiesFramesWithin(f, first, count)) continue;
    const auto size = static_cast<Eigen::Index>(kState * f.frames.size());
    const Eigen::MatrixXd& H = f.factor.information;
    const Eigen::VectorXd& g = f.factor.gradient;
    // 1/2 e^T H e + g^T e with e = d - d0 (d0: the linearisation's departure) = 1/2 d^T H d - (H d0 - g)^T d + const.
    Eigen::VectorXd d0 = f.factor.linearisation;
    for (Eigen::Index a = 0; a < size; ++a) d0[a] -= nominal[a % kState];
    const Eigen::VectorXd b = w * (H * d0 - g);
    for (Eigen::Index a = 0; a < size; ++a) {
      const Eigen::Index row = kState * (f.frames[static_cast<size_t>(a / kState)] - first) + a % kState;
      system.eta[row] += b[a];
      for (Eigen::Index c = 0; c < size; ++c) {
        const Eigen::Index column = kState * (f.frames[static_cast<size_t>(c / kState)] - first) + c % kState;
        system.entries.emplace_back(row, column, w * H(a, c));
      }
    }
  }
  return system;
}

/// The priors on the tilt and on the height.
struct Hypothesis {
  Rocking tilt, height;
};

struct Solution {
  Eigen::VectorXd departures;
  double evidence = -std::numeric_limits<double>::infinity();
};

/// The posterior mean under a hypothesis and log p(factors | hypothesis) up to a constant. steps[i] (window
/// frame i): the rocking steps since window frame i - 1, so the correlation between them is rho^steps[i].
std::optional<Solution> solve(const NormalEquations& system, const Hypothesis& h, const std::vector<double>& steps) {
  const int n = system.count;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(system.entries.size() + static_cast<size_t>(4 * kState * n));
  entries.insert(entries.end(), system.entries.begin(), system.entries.end());
  double prior_log_det = 0.0;
  for (int component = 0; component < kState; ++component) {
    const Rocking& r = component < 2 ? h.tilt : h.height;
    const double variance = r.sigma * r.sigma;
    // The AR(1) chain: x_0 ~ N(0, sigma^2), x_i | x_(i-1) ~ N(rho_i x_(i-1), sigma^2 (1 - rho_i^2)) with rho_i =
    // rho^steps_i. Its precision is tridiagonal; its log determinant -n log sigma^2 - sum log(1 - rho_i^2).
    // With every step 1 it is the textbook 1, 1 + rho^2, ..., 1 + rho^2, 1 over sigma^2 (1 - rho^2).
    entries.emplace_back(component, component, 1.0 / variance);
    for (int i = 1; i < n; ++i) {
      const double rho = r.correlation == 0.0 ? 0.0 : std::pow(r.correlation, steps[static_cast<size_t>(i)]);
      const double c = 1.0 / (variance * (1.0 - rho * rho));
      const Eigen::Index row = kState * i + component;
      entries.emplace_back(row, row, c);
      if (rho != 0.0) {
        entries.emplace_back(row - kState, row - kState, rho * rho * c);
        entries.emplace_back(row, row - kState, -rho * c);
        entries.emplace_back(row - kState, row, -rho * c);
      }
      prior_log_det -= std::log(1.0 - rho * rho);
    }
    prior_log_det -= n * std::log(variance);
  }
  const Eigen::Index size = kState * static_cast<Eigen::Index>(n);
  Eigen::SparseMatrix<double> A(size, size);
  A.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
  if (solver.info() != Eigen::Success) return std::nullopt;
  Solution solution;
  solution.departures = solver.solve(system.eta);
  if (solver.info() != Eigen::Success || !solution.departures.allFinite()) return std::nullopt;
  const Eigen::VectorXd d = solver.vectorD();
  if ((d.array() <= 0.0).any()) return std::nullopt;
  solution.evidence = 0.5 * system.eta.dot(solution.departures) - 0.5 * d.array().log().sum() + 0.5 * prior_log_det;
  if (!std::isfinite(solution.evidence)) return std::nullopt;
  return solution;
}

/// How far a factor's cost at the departures d stands above its own minimum, doubled: a chi-square with as many
/// degrees of freedom as the factor's information has rank, when the factor is right.
struct Misfit {
  double chi2 = 0.0;
  int rank = 0;
};

Misfit misfitOf(const FrameMountFactor& f, const Eigen::VectorXd& departures, const Eigen::Vector3d& nominal) {
  const auto size = static_cast<Eigen::Index>(kState * f.frames.size());
  Eigen::VectorXd e(size);  // departure from the factor's linearisation
  for (Eigen::Index a = 0; a < size; ++a) {
    e[a] = departures[kState * f.frames[static_cast<size_t>(a / kState)] + a % kState] + nominal[a % kState] - f.factor.linearisation[a];
  }
  const Eigen::MatrixXd& H = f.factor.information;
  const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> decomposition(H);
  const Eigen::VectorXd from_minimum = e + decomposition.solve(f.factor.gradient);  // the minimum: e = -H^+ g
  return {from_minimum.dot(H * from_minimum), static_cast<int>(decomposition.rank())};
}

/// The chi-square value a right factor of `dof` degrees of freedom exceeds as rarely as a standard normal exceeds
/// z (Wilson and Hilferty's cube-root normal approximation; z = 2.326: 1%).
double chiSquareQuantile(int dof, double z) {
  const double k = std::max(1, dof);
  const double c = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
  return k * c * c * c;
}

enum class Part { tilt, height };

/// The best value of one part of the hypothesis (the others held) by the evidence.
void choose(const NormalEquations& system, Hypothesis& h, Part part, const MountSmoothingSettings& settings,
            const std::vector<double>& steps) {
  double best = -std::numeric_limits<double>::infinity();
  Hypothesis chosen = h;
  const auto consider = [&](const Hypothesis& candidate) {
    const auto solution = solve(system, candidate, steps);
    if (solution && solution->evidence > best) best = solution->evidence, chosen = candidate;
  };
  const double max_sigma = part == Part::tilt ? settings.max_tilt_sigma_rad : settings.max_height_sigma_m;
  for (double rho : kCorrelations) {
    for (int k = 0; k < 8; ++k) {
      Hypothesis candidate = h;
      // Assigned by a plain if: GCC 12 with the sanitizers miscompiled `(cond ? a : b) = {...}` here (every
      // candidate got the last sigma).
      const Rocking rocking{max_sigma / std::pow(2.0, k), rho};
      if (part == Part::tilt) {
        candidate.tilt = rocking;
      } else {
        candidate.height = rocking;
      }
      consider(candidate);
    }
  }
  h = chosen;
}

}  // namespace

MountSmoothing smoothMounts(int frames, const std::vector<FrameMountFactor>& factors, const MountSmoothingSettings& settings,
                            const std::vector<double>& steps) {
  MountSmoothing result;
  if (frames <= 0 || !(settings.max_tilt_sigma_rad > 0.0) || !(settings.max_height_sigma_m > 0.0) ||
      !std::isfinite(settings.max_tilt_sigma_rad) || !std::isfinite(settings.max_height_sigma_m)) {
    return result;
  }
  // One step between frames unless told more (a missing, NaN or smaller value is one step; infinity: the
  // frames are independent, as across a lost frame).
  std::vector<double> all_steps(static_cast<size_t>(frames), 1.0);
  for (size_t i = 0; i < all_steps.size() && i < steps.size(); ++i) {
    if (!std::isnan(steps[i])) all_steps[i] = std::clamp(steps[i], 1.0, kMaxSteps);
  }
  const Eigen::Vector3d nominal(0.0, 0.0, settings.nominal_height_m);
  // The hypothesis is chosen on a window from the first frame with a factor (a bounded cost however long the
  // run), one part at a time: the tilt's prior, the height's, then both again.
  int first = frames;
  for (const FrameMountFactor& f : factors) {
    if (usable(f)) first = std::min(first, *std::min_element(f.frames.begin(), f.frames.end()));
  }
  first = std::clamp(first, 0, frames - 1);
  const int window = std::min(frames - first, std::max(1, settings.search_frames));
  const NormalEquations search = normalEquations(first, window, factors, nominal, true);
  const std::vector<double> search_steps(all_steps.begin() + first, all_steps.begin() + first + window);
  Hypothesis h{{settings.max_tilt_sigma_rad / 8.0, 0.8}, {settings.max_height_sigma_m / 8.0, 0.8}};
  for (Part part : {Part::tilt, Part::height, Part::tilt, Part::height}) choose(search, h, part, settings, search_steps);
  result.rocking = {h.tilt, h.height};
  result.plausible = h.tilt.sigma < settings.max_tilt_sigma_rad * (1.0 - 1e-9);
  // The whole run, with every factor (the search's own system when it already holds them all).
  const bool search_holds_all = first == 0 && window == frames &&
                                std::all_of(factors.begin(), factors.end(), [](const FrameMountFactor& f) { return f.chooses_priors; });
  auto solution = search_holds_all ? solve(search, h, all_steps)
                                   : solve(normalEquations(0, frames, factors, nominal, false), h, all_steps);
  if (!solution) return result;
  // A factor far above what its own information allows (an estimate misled by the robot's shadow, or a mount that
  // jumped between frames where the pairs could not see it) pulls its frames off: it is down-weighted by
  // chi2_limit / chi2 and the run solved again (iteratively reweighted; its weight only falls).
  if (settings.robust_outlier_z > 0.0) {
    std::vector<double> weights(factors.size(), 1.0);
    for (int iteration = 0; iteration < kRobustIterations; ++iteration) {
      bool changed = false;
      for (size_t k = 0; k < factors.size(); ++k) {
        if (!usable(factors[k]) || !tiesFramesWithin(factors[k], 0, frames)) continue;
        const Misfit m = misfitOf(factors[k], solution->departures, nominal);
        const double limit = chiSquareQuantile(m.rank, settings.robust_outlier_z);
        const double chi2 = weights[k] * m.chi2;
        if (chi2 > limit) {
          weights[k] *= limit / chi2;
          changed = true;
        }
      }
      if (!changed) break;
      const auto reweighted = solve(normalEquations(0, frames, factors, nominal, false, weights), h, all_steps);
      if (!reweighted) break;
      solution = reweighted;
    }
  }
  result.states.resize(static_cast<size_t>(frames));
  for (int i = 0; i < frames; ++i) {
    const Eigen::Vector3d state = solution->departures.segment<kState>(kState * i) + nominal;
    result.states[static_cast<size_t>(i)] = {state.x(), state.y(), state.z()};
  }
  return result;
}

}  // namespace groundslam
