#pragma once
// Not in the paper: the camera's roll, pitch and height above the ground, estimated per frame. A rocking
// mount shifts every ground point by height x tilt (2 mm for 0.5 degrees at 25 cm), which an SE(2) fit
// cannot tell from motion. Two views of the same ground plane fix both cameras' attitude through the
// perspective of the plane (the plane-induced homography has 8 degrees of freedom: motion 3, attitude 2 + 2,
// height ratio 1); the baseline between the views decides how well.

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "groundslam/core/Pose2.hpp"

namespace groundslam {

/// The camera's attitude and height in one frame: the calibrated mount turned by roll (about the robot's
/// x axis) and pitch (about its y axis), its optical centre at `height_m` above the ground.
struct MountState {
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
  double height_m = 0.0;
};

/// The calibrated mount (T_robot_camera) in a given state.
Eigen::Isometry3d mountFor(const Eigen::Isometry3d& calibrated, const MountState& state);

/// The calibrated mount's own state: no tilt, its height.
MountState calibratedState(const Eigen::Isometry3d& calibrated);

struct MountEstimationSettings {
  double tilt_prior_rad = 0.035;       ///< standard deviation of the tilt around the calibrated mount (2 degrees)
  double height_prior_m = 0.003;       ///< standard deviation of the height around the calibrated height
  double reference_sigma_rad = 0.003;  ///< how well the reference frame's attitude is already known
  double point_sigma_m = 0.0002;       ///< noise of a ground point, metres (about a third of a pixel at 320x240)
  /// Subsampling of the matched pairs: every floor(n / max_pairs)-th, so between max_pairs and 2 max_pairs - 1
  /// pairs when there are more. (Measured: capping at exactly 300 raised the asphalt loop's ATE from 2.17 to 2.71 mm.)
  int max_pairs = 300;
  int min_pairs = 30;                  ///< fewer pairs: no estimate
};

/// What one estimate says about the true states of its frames, the motions marginalised out and no prior
/// included: the cost 1/2 d^T information d + gradient^T d, d = states - linearisation, with states = (roll,
/// pitch, height) of the current frame, then of each reference in `observations` order (those with pairs). Two
/// views fix the rotation between them well, the plane's orientation and the heights' common scale poorly:
/// `information` is close to singular along those.
struct MountFactor {
  std::vector<int> observations;  ///< which observation each reference block is
  Eigen::VectorXd linearisation, gradient;
  Eigen::MatrixXd information;
};

struct MountEstimate {
  bool ok = false;
  MountState current;             ///< the current frame's state
  MountState reference;           ///< the reference frame's state, refined
  Pose2 T_reference_current;      ///< the robot's motion between the two frames
  Eigen::Matrix2d tilt_covariance = Eigen::Matrix2d::Identity();  ///< of the current (roll, pitch), rad^2
  double height_variance = 1.0;   ///< of the current height, m^2
  int pairs = 0;
  MountFactor factor;
};

/// Matched normalised camera rays of a reference frame and the current one (ray i of each sees the same
/// ground point), the reference's believed state and a guess of the motion between them.
struct MountObservation {
  std::vector<Eigen::Vector2d> reference_rays, current_rays;
  MountState reference;
  Pose2 T_guess;
  double point_sigma_m = 0.0;  ///< noise of these pairs' points; 0: settings.point_sigma_m
};

/// Estimates the current frame's mount state from its matches to one or more reference frames. The
/// references' heights are held (they fix the scale); their attitudes are refined within reference_sigma_rad. The result's `reference` and `T_reference_current` are the first observation's.
MountEstimate estimateMount(const std::vector<MountObservation>& observations, const Eigen::Isometry3d& calibrated,
                            const MountEstimationSettings& settings);
/// One reference frame.
MountEstimate estimateMount(const std::vector<Eigen::Vector2d>& reference_rays, const std::vector<Eigen::Vector2d>& current_rays,
                            const Eigen::Isometry3d& calibrated, const MountState& reference, const Pose2& T_guess,
                            const MountEstimationSettings& settings);

}  // namespace groundslam
