#pragma once
// Not in the paper: where the robot can have gone since the previous frame, from its own recent steps. On a
// repeated floor the matches support the true motion and its repetitions alike (one tile over); the robot's
// motion tells them apart: a frame later it has made about one more step, and over frames dropped without a
// trace about k of them, turning as it was turning.

#include <optional>
#include <vector>

#include "groundslam/core/Pose2.hpp"

namespace groundslam {

struct MotionPriorSettings {
  double turn_doubt_rad = 1.0 * 0.017453292519943295;  ///< over a gap, k usual steps turn as the motion does within this
  /// One step turns as the usual one within this, or turns on the spot by at least spin_min_rad (a sharp turn);
  /// between the two, a sudden turn is more likely a gap than one step.
  double step_turn_doubt_rad = 5.0 * 0.017453292519943295;
  double spin_min_rad = 70.0 * 0.017453292519943295;
  double sigma_m = 0.004;          ///< doubt of any prediction (a single fit is millimetres off on a rocking mount)
  double sigma_fraction = 0.2;     ///< and per step, this share of the usual step's length (speed changes)
  /// The tilt's lever arm, metres per radian of turn chord (height * tilt bound): a turn by theta adds
  /// 2 |sin(theta / 2)| times this to the doubt.
  double lever_m = 0.0;
  double max_doubts = 1.0;  ///< the chosen candidate is at most this many doubts off,
  double margin = 2.5;      ///< and every other at least this many times as far (and as many doubts) off
  /// Failing that, the candidate within max_doubts with the most support is chosen when it has at least this
  /// many times the support of every other candidate the prior does not rule out (closer than margin *
  /// max_doubts): a tile over, a gap's repetition overlaps the image less. 0 = off.
  double support_ratio = 2.0;
};

/// A predicted motion and its doubt (one standard deviation of its translation, metres).
struct PredictedMotion {
  Pose2 T_prev_curr;
  int steps = 1;
  double sigma_m = 0.0;
};

class MotionPrior {
 public:
  /// `usual_step`: the robot's motion between consecutive frames lately; steps from first_steps to last_steps
  /// are considered (both 1 when the timestamps show that no frame is missing; both k when they show a gap of k).
  MotionPrior(const Pose2& usual_step, int first_steps, int last_steps, const MotionPriorSettings& settings);
  /// Several usual steps the robot may be making (after a turn on the spot: its steps as before, or turned with it).
  MotionPrior(std::vector<Pose2> usual_steps, int first_steps, int last_steps, const MotionPriorSettings& settings);

  /// The motions the robot can have made if it turned by `theta` in all: one usual step, turning as usual or on
  /// the spot, or k steps each turning by theta / k where k usual turns make theta.
  std::vector<PredictedMotion> predictions(double theta_rad) const;
  /// How far a motion is from the nearest prediction with its turn, in doubts; infinity when none applies.
  double doubtsOff(const Pose2& T_prev_curr) const;
  /// The same, where one step may also turn by any angle (a sudden change of the turn rate).
  double looseDoubtsOff(const Pose2& T_prev_curr) const;
  /// The index of the nearest candidate when it is at most max_doubts off and every other at least `margin`
  /// times as far (and `margin` doubts) off; else, given each candidate's `support` (its inliers), the likeliest
  /// one when it has support_ratio times the support of every other candidate closer than margin * max_doubts
  /// (judged by looseDoubtsOff) and, when only a sudden change of turn makes it a step, no less than any
  /// candidate; none otherwise.
  std::optional<size_t> choose(const std::vector<Pose2>& candidates, const std::vector<int>& support = {}) const;
  /// The best supported candidate within max_doubts, however close the others: of those whose turn the steps
  /// explain (doubtsOff) if any, else of those within looseDoubtsOff. The likeliest motion where choose() believes
  /// none; none when no candidate is within max_doubts.
  std::optional<size_t> likeliest(const std::vector<Pose2>& candidates, const std::vector<int>& support) const;

 private:
  std::vector<Pose2> steps_;
  int first_steps_, last_steps_;
  MotionPriorSettings settings_;
};

}  // namespace groundslam
