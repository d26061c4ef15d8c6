#pragma once
// Not in the paper: the camera's roll, pitch and height over the whole run at once. One frame's estimate
// (core/MountEstimation) knows its state relative to its references far better than absolutely: two views of
// the ground show the rotation and the change of scale between them clearly, the plane's orientation only
// through a baseline of a centimetre or so, and the heights' common scale not at all. Solving every frame's
// state together from all the estimates' factors, under a prior that the mount rocks and bounces around its
// calibration, keeps the relative precision and pins the level with the whole run.

#include <vector>

#include "groundslam/core/MountEstimation.hpp"

namespace groundslam {

/// A MountFactor tied to frames: frames[0] is its current frame, then its references.
struct FrameMountFactor {
  std::vector<int> frames;
  MountFactor factor;
  /// False for a loop closure's factor: it ties frames far apart and joins the solution, but the priors are
  /// chosen without it (the frame-to-frame estimates tell how the mount rocks; measured: with loop factors
  /// choosing too, a weak concrete texture under shadow and glare looked like a rocking mount and its solved
  /// tilt made the held-out seed-29 concrete loop worse, 3.24 -> 3.85 mm).
  bool chooses_priors = true;
};

/// A stationary AR(1) process around the calibrated mount: standard deviation `sigma`, each frame keeping
/// `correlation` of the previous frame's departure.
struct Rocking {
  double sigma = 0.0;
  double correlation = 0.0;
};

struct MountSmoothingSettings {
  double nominal_height_m = 0.25;     ///< the calibrated height (the tilt's nominal value is zero)
  double max_tilt_sigma_rad = 0.035;  ///< the widest tilt prior tried (then halved, 8 values)
  double max_height_sigma_m = 0.003;  ///< the widest height prior tried (then halved, 8 values)
  int search_frames = 600;            ///< the priors are chosen on this many frames (the first with factors)
  /// A factor whose misfit exceeds the chi-square value a right one exceeds with the normal tail of this z is
  /// down-weighted (0: every factor at full weight).
  double robust_outlier_z = 2.326;
};

/// How a mount moves around its calibration: its tilt (radians, roll and pitch alike) and its height (metres).
struct MountRocking {
  Rocking tilt;
  Rocking height;
};

struct MountSmoothing {
  std::vector<MountState> states;  ///< per frame; empty when nothing could be solved
  MountRocking rocking;            ///< the priors chosen: how the mount rocks and bounces, as the factors tell
  /// False when only the widest tilt prior (max_tilt_sigma_rad, the bound on the mount's rocking) explains the
  /// factors: not a rocking mount but images that misled every estimate alike (measured: a weak texture under
  /// the robot's shadow, glare and a bumper, where the solved tilt was worse than none). Such states are not
  /// to be used.
  bool plausible = false;
};

/// Every frame's state, frames 0 .. frames-1 in the order they were taken, minimising the factors' costs (a
/// factor naming another frame is ignored) under AR(1) priors on the tilt (roll and pitch alike) and on the
/// height. Each prior's sigma and correlation (0 to 0.98) are chosen by the factors' marginal likelihood: a
/// rigid mount gets small priors, so its frames stay at the calibration instead of following the estimates' noise.
/// Then a factor far above what its own information allows (settings.robust_outlier_z) is down-weighted and the
/// run solved again (iteratively reweighted, five rounds at most; the priors stay as chosen).
/// steps[i]: how many of the prior's steps lie between frames i - 1 and i (1 when absent; frames dropped
/// between them, or a jump in speed that says so, make it more): their correlation is then correlation^steps.
MountSmoothing smoothMounts(int frames, const std::vector<FrameMountFactor>& factors, const MountSmoothingSettings& settings,
                            const std::vector<double>& steps = {});

}  // namespace groundslam
