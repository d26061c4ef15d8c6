// Metrics on trajectories whose errors are known exactly.
#include <cmath>

#include <gtest/gtest.h>

#include "groundslam/eval/LoopClosureMetrics.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"

using namespace groundslam;

namespace {

Trajectory straightLine(int n, double step) {
  Trajectory t;
  for (int i = 0; i < n; ++i) t.push_back({static_cast<double>(i), Pose2(step * i, 0.0, 0.0)});
  return t;
}

}  // namespace

TEST(TrajectoryMetrics, PerfectEstimateInAnotherFrameHasZeroError) {
  const Trajectory truth = straightLine(11, 0.1);
  Trajectory estimate;
  const Pose2 offset(5.0, -2.0, 1.0);  // the estimate starts at its own origin: anchoring removes this
  for (const auto& p : truth) estimate.push_back({p.timestamp, offset * p.T_world_robot});
  const TrajectoryMetrics m = evaluateTrajectory(truth, estimate).metrics;
  EXPECT_EQ(m.paired_frames, 11);
  EXPECT_DOUBLE_EQ(m.fraction_estimated, 1.0);
  EXPECT_NEAR(m.path_length_m, 1.0, 1e-12);
  EXPECT_NEAR(m.translation_mae_m, 0.0, 1e-12);
  EXPECT_NEAR(m.rotation_mae_deg, 0.0, 1e-9);
  EXPECT_NEAR(m.ate_rmse_m, 0.0, 1e-12);
}

TEST(TrajectoryMetrics, ConstantLateralOffsetAfterTheFirstPose) {
  // Every pose after the first is 1 cm to the left: MAE = 10 * 0.01 / 11, over a 1 m path.
  const Trajectory truth = straightLine(11, 0.1);
  Trajectory estimate = truth;
  for (size_t i = 1; i < estimate.size(); ++i) estimate[i].T_world_robot.y += 0.01;
  const TrajectoryMetrics m = evaluateTrajectory(truth, estimate).metrics;
  EXPECT_NEAR(m.translation_mae_m, 0.1 / 11.0, 1e-12);
  EXPECT_NEAR(m.translation_mae_cm_per_m, 100.0 * 0.1 / 11.0, 1e-9);
  // Only the first step is wrong, by 1 cm.
  EXPECT_NEAR(m.rpe_translation_rmse_m, 0.01 / std::sqrt(10.0), 1e-12);
}

TEST(TrajectoryMetrics, AteAfterBestAlignment) {
  // 1 cm errors at both ends and the middle of a line: symmetric, so no rotation helps and the best
  // alignment shifts by the mean error c = 3/11 cm.
  const Trajectory truth = straightLine(11, 0.1);
  Trajectory estimate = truth;
  for (size_t i : {0u, 5u, 10u}) estimate[i].T_world_robot.y += 0.01;
  const double c = 0.03 / 11.0;
  const double expected = std::sqrt((3.0 * (0.01 - c) * (0.01 - c) + 8.0 * c * c) / 11.0);
  EXPECT_NEAR(evaluateTrajectory(truth, estimate).metrics.ate_rmse_m, expected, 1e-12);
}

TEST(TrajectoryMetrics, HeadingErrorAndAnchoring) {
  // The estimate turned by 2 degrees at the start: anchoring the first pose leaves the rotation error
  // on every pose, and positions swing away from the line by 2 degrees.
  const Trajectory truth = straightLine(5, 1.0);
  const double a = 2.0 * M_PI / 180.0;
  Trajectory estimate;
  for (const auto& p : truth) estimate.push_back({p.timestamp, Pose2(p.T_world_robot.x * std::cos(a), p.T_world_robot.x * std::sin(a), a)});
  // First estimate already carries the 2 degrees: anchoring rotates it all back, so zero error.
  EXPECT_NEAR(evaluateTrajectory(truth, estimate).metrics.rotation_mae_deg, 0.0, 1e-9);
  // Now the heading is right at the start and wrong afterwards.
  estimate[0].T_world_robot = truth[0].T_world_robot;
  const TrajectoryMetrics m = evaluateTrajectory(truth, estimate).metrics;
  EXPECT_NEAR(m.rotation_mae_deg, 2.0 * 4.0 / 5.0, 1e-9);
  double mae = 0.0;
  for (int i = 1; i < 5; ++i) mae += 2.0 * i * std::sin(a / 2.0);
  EXPECT_NEAR(m.translation_mae_m, mae / 5.0, 1e-12);
}

TEST(TrajectoryMetrics, AlignmentIsAProperRotationEvenForMirroredData) {
  std::vector<Eigen::Vector2d> from = {{0, 0}, {1, 0}, {0, 1}}, to = {{0, 0}, {1, 0}, {0, -1}};
  const Pose2 T = alignSE2(from, to);
  EXPECT_TRUE(std::isfinite(T.theta));
  // A mirror would fit exactly; a rotation cannot, so some residual stays.
  double residual = 0.0;
  for (size_t i = 0; i < 3; ++i) residual += (T * from[i] - to[i]).norm();
  EXPECT_GT(residual, 0.5);
}

TEST(TrajectoryMetrics, PairsByTimestampAndCountsMissingFrames) {
  const Trajectory truth = straightLine(10, 0.1);
  Trajectory estimate(truth.begin(), truth.begin() + 6);
  for (auto& p : estimate) p.timestamp += 0.0004;  // within the default 1 ms
  const TrajectoryMetrics m = evaluateTrajectory(truth, estimate).metrics;
  EXPECT_EQ(m.paired_frames, 6);
  EXPECT_DOUBLE_EQ(m.fraction_estimated, 0.6);
  EXPECT_EQ(evaluateTrajectory(truth, estimate, 1e-4).metrics.paired_frames, 0);
}

TEST(LoopClosureMetrics, NothingAcceptedIsNullNotPerfect) {
  // Two verified candidates, both rejected; one of them was true (its footprints overlap).
  std::vector<LoopCandidate> candidates(2);
  candidates[0].rejected_by = LoopGate::covariance;
  candidates[1].rejected_by = LoopGate::bow_score;
  CandidateTruth overlapping;
  overlapping.footprints_overlap = true;
  const std::vector<std::optional<CandidateTruth>> truths = {overlapping, CandidateTruth{}};
  const LoopClosureMetrics m = summariseLoopClosures(candidates, truths);
  EXPECT_EQ(m.verified, 2);
  EXPECT_EQ(m.accepted, 0);
  EXPECT_TRUE(std::isnan(m.precision));
  EXPECT_DOUBLE_EQ(m.recall, 0.0);
  const std::string json = loopMetricsToJson(m);
  EXPECT_NE(json.find("\"precision\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"recall\": 0.000000"), std::string::npos) << json;
  EXPECT_NE(json.find("\"mean_translation_error_m\": null"), std::string::npos) << json;
  const std::string text = loopMetricsToText(m);
  EXPECT_NE(text.find("precision / recall  n/a / 0.000"), std::string::npos) << text;
  EXPECT_NE(text.find("mean n/a mm, n/a deg"), std::string::npos) << text;
  // With no true candidate either, recall has nothing to measure.
  EXPECT_NE(loopMetricsToJson(summariseLoopClosures({}, {})).find("\"recall\": null"), std::string::npos);
}

TEST(LoopClosureMetrics, FootprintOverlapIsTheExactAreaAlongALane) {
  // An 18 x 14 cm footprint, its border sampled as the camera model samples it (collinear points on every side).
  std::vector<Eigen::Vector2d> footprint;
  const Eigen::Vector2d corners[4] = {{-0.09, -0.07}, {0.09, -0.07}, {0.09, 0.07}, {-0.09, 0.07}};
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < 8; ++k) footprint.push_back(corners[side] + (corners[(side + 1) % 4] - corners[side]) * (k / 8.0));
  }
  // Two frames 9 cm apart on a lawnmower lane driven at 179.96 degrees (the long edges on nearly the same lines:
  // OpenCV's intersectConvexConvex gave 0 here and the right loop closure between them counted as wrong).
  const double heading = 2.0 * std::atan2(0.999999935010, 0.000360526857);
  const Pose2 a(0.098779609609, 0.082128713845, heading), b(0.008779633005, 0.082193608675, heading);
  EXPECT_NEAR(footprintOverlap(footprint, a, b), 0.09 * 0.14, 1e-6);
  EXPECT_NEAR(footprintOverlap(footprint, a, a), 0.18 * 0.14, 1e-9);
  // Turned a quarter on the spot: the 14 x 14 cm square they share.
  EXPECT_NEAR(footprintOverlap(footprint, Pose2(0.0, 0.0, 0.0), Pose2(0.0, 0.0, M_PI / 2)), 0.14 * 0.14, 1e-9);
  // Side by side, 18 cm apart along x: touching, no overlap; 19 cm: none.
  EXPECT_NEAR(footprintOverlap(footprint, Pose2(0.0, 0.0, 0.0), Pose2(0.18, 0.0, 0.0)), 0.0, 1e-12);
  EXPECT_EQ(footprintOverlap(footprint, Pose2(0.0, 0.0, 0.0), Pose2(0.19, 0.0, 0.0)), 0.0);
}
