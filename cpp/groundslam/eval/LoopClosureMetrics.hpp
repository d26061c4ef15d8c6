#pragma once
// Loop-closure diagnostics against ground truth: is a candidate a true revisit (the two image
// footprints overlap on the ground), and how far off is an accepted loop transform?

#include <cmath>
#include <optional>
#include <vector>

#include "groundslam/core/Pose2.hpp"
#include "groundslam/core/Trajectory.hpp"
#include "groundslam/pipeline/LoopClosure.hpp"

namespace groundslam {

struct CandidateTruth {
  double distance_m = 0.0;          ///< between the two robots' true positions
  bool footprints_overlap = false;  ///< a true loop closure
  double translation_error_m = 0.0; ///< |T_a_b estimated - T_a_b true| (accepted candidates)
  double rotation_error_deg = 0.0;
};

/// `footprint` is the image's footprint in the robot frame (CameraModel::groundFootprint).
CandidateTruth candidateTruth(const LoopCandidate& candidate, const Pose2& true_T_world_a, const Pose2& true_T_world_b,
                              const std::vector<Eigen::Vector2d>& footprint);

/// Overlap area (m^2) of the footprints of two robot poses.
double footprintOverlap(const std::vector<Eigen::Vector2d>& footprint, const Pose2& T_world_a, const Pose2& T_world_b);

/// The truth of every candidate: frames are located by index in `frame_timestamps`, then by timestamp in
/// the ground truth; a candidate with a frame lacking ground truth gets none.
std::vector<std::optional<CandidateTruth>> candidateTruths(const std::vector<LoopCandidate>& candidates,
                                                           const std::vector<double>& frame_timestamps,
                                                           const std::vector<StampedPose>& groundtruth,
                                                           const std::vector<Eigen::Vector2d>& footprint);

struct LoopClosureMetrics {
  int verified = 0;             ///< candidates with ground truth at both frames
  int accepted = 0;
  int true_candidates = 0;      ///< verified candidates whose footprints overlap
  int true_positives = 0;       ///< accepted and overlapping
  int wrong_accepted = 0;       ///< accepted but not overlapping, or more than 2 cm / 2 deg off
  // NaN when there is nothing to measure (null in JSON, n/a in text): precision and the errors when no
  // candidate was accepted, recall when no candidate was true.
  double precision = std::nan("");  ///< true positives / accepted
  double recall = std::nan("");     ///< true positives / true candidates
  double mean_translation_error_m = std::nan("");  ///< over accepted loop transforms
  double max_translation_error_m = std::nan("");
  double mean_rotation_error_deg = std::nan("");
  double max_rotation_error_deg = std::nan("");
};

LoopClosureMetrics summariseLoopClosures(const std::vector<LoopCandidate>& candidates,
                                         const std::vector<std::optional<CandidateTruth>>& truths);

std::string loopMetricsToJson(const LoopClosureMetrics& metrics);
std::string loopMetricsToText(const LoopClosureMetrics& metrics);

}  // namespace groundslam
