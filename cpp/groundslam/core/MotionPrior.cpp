#include "groundslam/core/MotionPrior.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace groundslam {

MotionPrior::MotionPrior(const Pose2& usual_step, int first_steps, int last_steps, const MotionPriorSettings& settings)
    : step_(usual_step), first_steps_(std::max(1, first_steps)), last_steps_(last_steps), settings_(settings) {}

std::vector<PredictedMotion> MotionPrior::predictions(double theta_rad) const {
  std::vector<PredictedMotion> predicted;
  const double length = step_.translation().norm();
  const double lever_m = 2.0 * std::abs(std::sin(0.5 * theta_rad)) * settings_.lever_m;
  for (int k = first_steps_; k <= last_steps_; ++k) {
    const double turn_per_step = theta_rad / k;
    if (k > 1 && std::abs(wrapAngle(theta_rad - k * step_.theta)) > settings_.turn_doubt_rad) continue;
    if (k == 1 && std::abs(wrapAngle(theta_rad - step_.theta)) > settings_.step_turn_doubt_rad &&
        std::abs(wrapAngle(theta_rad)) < settings_.spin_min_rad) {
      continue;
    }
    // One step keeps its translation whatever the turn; k steps turn evenly, each moving as the usual step.
    const Pose2 one_step(step_.x, step_.y, k > 1 ? turn_per_step : 0.0);
    Pose2 motion;
    for (int j = 0; j < k; ++j) motion = motion * one_step;
    motion.theta = theta_rad;
    predicted.push_back({motion, k, settings_.sigma_m + settings_.sigma_fraction * k * length + lever_m});
  }
  return predicted;
}

double MotionPrior::doubtsOff(const Pose2& T_prev_curr) const {
  double best = std::numeric_limits<double>::infinity();
  for (const PredictedMotion& p : predictions(T_prev_curr.theta)) {
    best = std::min(best, (p.T_prev_curr.translation() - T_prev_curr.translation()).norm() / p.sigma_m);
  }
  return best;
}

std::optional<size_t> MotionPrior::choose(const std::vector<Pose2>& candidates) const {
  std::optional<size_t> chosen;
  double chosen_off = std::numeric_limits<double>::infinity(), next_off = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < candidates.size(); ++i) {
    const double off = doubtsOff(candidates[i]);
    if (off < chosen_off) {
      next_off = chosen_off;
      chosen_off = off;
      chosen = i;
    } else {
      next_off = std::min(next_off, off);
    }
  }
  if (!chosen || !(chosen_off <= settings_.max_doubts) || next_off < settings_.margin * std::max(1.0, chosen_off)) return std::nullopt;
  return chosen;
}

}  // namespace groundslam
