#pragma once
// What the pipeline reports for each processed frame.

#include <string>

#include "groundslam/core/MountEstimation.hpp"
#include "groundslam/core/Pose2.hpp"
#include "groundslam/core/RigidFit.hpp"

namespace groundslam {

/// Milliseconds spent in each stage of one frame.
struct StageTimes {
  double extract_ms = 0.0;   ///< ORB detection and description
  double project_ms = 0.0;   ///< keypoints to ground points
  double match_ms = 0.0;     ///< descriptor matching to the previous frame
  double fit_ms = 0.0;       ///< robust SE(2) fit and covariance
  double loop_ms = 0.0;      ///< loop-closure search and verification
  double optimise_ms = 0.0;  ///< pose-graph optimisation
  double total_ms = 0.0;
};

/// What became of a frame.
enum class FrameStatus {
  first,        ///< the first frame of the session: the origin
  ok,           ///< odometry measured the motion from the previous frame
  low_overlap,  ///< odometry measured it from a second, looser matching of a low-overlap pair: less certain
  aligned,      ///< too few features: the motion was measured by aligning the two images themselves: less certain
  unconfirmed,  ///< odometry measured it from a few dozen keypoints that aligning the images did not confirm: less certain
  uncertain,    ///< odometry measured it, but the fit's own covariance does not vouch for the `ok` tolerance
  sharp_turn,   ///< odometry measured it, but the turn is so sharp that the unknown tilt may move it by millimetres
  gap,          ///< odometry measured it across dropped frames (several frames' travel): the mount rocked meanwhile
  fallback,     ///< odometry failed (FrameResult::fallback_reason); the previous motion was assumed
  lost,         ///< tracking is lost: the pose is unknown until global localization finds it
  relocalized,  ///< global localization found the pose again (tracking resumes)
};

/// Odometry measured the frame's motion with its first matching (`sharp_turn`, `gap`, `unconfirmed` and `uncertain`
/// only say it is less certain).
inline bool measuredByOdometry(FrameStatus status) {
  return status == FrameStatus::ok || status == FrameStatus::sharp_turn || status == FrameStatus::gap ||
         status == FrameStatus::unconfirmed || status == FrameStatus::uncertain;
}

struct FrameResult {
  int index = 0;
  double timestamp = 0.0;
  int keypoints = 0;          ///< ground points kept
  int matches = 0;            ///< ratio-test matches to the previous frame
  int inliers = 0;            ///< matches consistent with the fitted motion
  FrameStatus status = FrameStatus::first;
  FitStatus fallback_reason = FitStatus::ok;  ///< why odometry failed (status fallback, or lost on the frame whose odometry failed)
  Pose2 T_world_robot;        ///< the estimate when the frame was processed
  int loop_closures = 0;      ///< accepted loop closures of this frame
  Pose2 odometry;             ///< the odometry edge's motion from the previous frame (meaningful when status is ok)
  int still_matches = 0;      ///< matches that stayed still in the image while the robot moved (not ground)
  int artifact_cells = 0;     ///< image cells the artifact mask excludes
  MountState mount;           ///< the camera's roll, pitch and height used for this frame's ground points
  bool mount_estimated = false;  ///< mount was estimated from the images (else the calibrated mount)
  StageTimes times;
  /// frames.csv's `status`: first | ok | low_overlap | aligned | unconfirmed | uncertain | sharp_turn | gap | fallback_<reason> (e.g. fallback_too_few_matches) | lost_<reason> (the
  /// frame whose failed odometry lost tracking, e.g. lost_degenerate) | lost (a later frame of a lost segment) | relocalized.
  std::string statusName() const {
    switch (status) {
      case FrameStatus::first: return "first";
      case FrameStatus::ok: return "ok";
      case FrameStatus::low_overlap: return "low_overlap";
      case FrameStatus::aligned: return "aligned";
      case FrameStatus::unconfirmed: return "unconfirmed";
      case FrameStatus::uncertain: return "uncertain";
      case FrameStatus::sharp_turn: return "sharp_turn";
      case FrameStatus::gap: return "gap";
      case FrameStatus::fallback: return std::string("fallback_") + fitStatusName(fallback_reason);
      case FrameStatus::lost: return fallback_reason == FitStatus::ok ? "lost" : std::string("lost_") + fitStatusName(fallback_reason);
      case FrameStatus::relocalized: return "relocalized";
    }
    return "unknown";
  }
};

}  // namespace groundslam
