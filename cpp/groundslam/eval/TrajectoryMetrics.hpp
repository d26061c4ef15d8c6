#pragma once
// Trajectory accuracy: the paper's normalised translational MAE and rotational MAE (first estimated
// pose anchored to the first ground-truth pose), ATE after the best SE(2) alignment, and RPE.

#include <string>
#include <vector>

#include "groundslam/core/Trajectory.hpp"

namespace groundslam {

struct TrajectoryMetrics {
  int groundtruth_frames = 0;         ///< frames with ground truth
  int paired_frames = 0;              ///< of those, frames with an estimate at the same time
  double fraction_estimated = 0.0;    ///< paired / ground-truth frames
  int measured_frames = 0;            ///< of the paired frames, those whose estimate was measured (not a fallback)
  double fraction_measured = 0.0;     ///< measured / ground-truth frames: the coverage the run achieved
  double path_length_m = 0.0;         ///< ground-truth path length over the paired frames
  double translation_mae_m = 0.0;     ///< mean |t_est - t_gt| with the first poses anchored
  double translation_mae_cm_per_m = 0.0;  ///< the paper's figure: MAE / path length, cm per metre (NaN: no path)
  double rotation_mae_deg = 0.0;      ///< mean |theta_est - theta_gt| with the first poses anchored
  double ate_rmse_m = 0.0;            ///< RMSE of positions after the best rigid SE(2) alignment
  double rpe_translation_rmse_m = 0.0;  ///< RMSE of consecutive relative-motion translation errors
  double rpe_rotation_rmse_deg = 0.0;   ///< RMSE of consecutive relative-motion rotation errors
};

/// One paired frame's errors after anchoring (for plots of error over the run).
struct FrameError {
  double timestamp = 0.0;
  double translation_m = 0.0;
  double rotation_deg = 0.0;
};

struct TrajectoryEvaluation {
  TrajectoryMetrics metrics;
  std::vector<FrameError> frame_errors;
};

/// Pairs poses whose timestamps differ by at most `max_time_difference` and computes the metrics. With no
/// pair, every error is NaN (there is nothing to compare, which is not a perfect result): callers check
/// `paired_frames` and say so.
TrajectoryEvaluation evaluateTrajectory(const Trajectory& groundtruth, const Trajectory& estimate,
                                        double max_time_difference = 1e-3);

/// The best proper rigid transform T (no mirror, no scale) with T * from_i ~ to_i.
Pose2 alignSE2(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to);

/// JSON with null for a figure that is not a number (JSON has no NaN).
std::string metricsToJson(const TrajectoryMetrics& metrics);
std::string metricsToText(const TrajectoryMetrics& metrics);

}  // namespace groundslam
