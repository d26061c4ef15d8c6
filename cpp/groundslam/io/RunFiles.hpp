#pragma once
// The loop-closure and graph files of a run folder.

#include <optional>
#include <string>
#include <vector>

#include "groundslam/core/PoseGraph.hpp"
#include "groundslam/core/Trajectory.hpp"
#include "groundslam/eval/LoopClosureMetrics.hpp"
#include "groundslam/pipeline/LoopClosure.hpp"

namespace groundslam {

/// `loop_closures.csv`: frame_a,frame_b,x,y,theta,bow_score,matches,covariance_score (accepted only);
/// (x, y, theta) is T_a_b, the pose of frame b's robot in frame a's robot frame.
std::string formatLoopClosuresCsv(const std::vector<LoopCandidate>& candidates);

/// `candidates.csv`: every verified candidate with its three scores and the gate that rejected it;
/// with ground truth also true_distance_m, footprints_overlap and the transform errors.
std::string formatCandidatesCsv(const std::vector<LoopCandidate>& candidates,
                                const std::vector<std::optional<CandidateTruth>>& truths);
/// Reads the candidates back (scores, gate, transform). Throws InputError naming file and line.
std::vector<LoopCandidate> readCandidatesCsv(const std::string& path);

/// `relocalizations.csv`: every global localization of a lost frame, in order:
/// frame,status,outcome,x,y,theta,votes,runner_up_votes,inliers,strong_inliers,runner_up_inliers. `status` is the
/// localizer's answer (localized, or why not: too_few_votes, ambiguous, too_few_inliers, covariance, clustered),
/// `outcome` what came of it (joined, pending, on_a_keyframe, not_localized, joined_nearby); (x, y, theta) the pose
/// found in the map frame, empty when no peak was verified (too_few_votes).
std::string formatRelocalizationsCsv(const std::vector<RelocalizationAttempt>& attempts);

/// Marks the poses of frames whose `frames.csv` status is a fallback as not measured (paired by timestamp).
/// Throws InputError naming file and line.
void markUnmeasuredPoses(const std::string& frames_csv_path, Trajectory& trajectory);

/// `graph.g2o`: VERTEX_SE2 id x y theta, EDGE_SE2 a b dx dy dtheta I11 I12 I13 I22 I23 I33.
std::string formatG2o(const PoseGraph& graph);

}  // namespace groundslam
