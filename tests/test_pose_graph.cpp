// Pose-graph optimisation: a known optimum from wrong initial guesses, and robustness to a wrong loop.
#include <cmath>

#include <gtest/gtest.h>

#include "groundslam/core/PoseGraph.hpp"

using namespace groundslam;

namespace {

const Eigen::Matrix3d kInformation = Eigen::Vector3d(100.0, 100.0, 400.0).asDiagonal();

/// GTSAM's Pose2SLAM example: a 2 m square driven counter-clockwise, closed by a loop edge from 5 to 2.
PoseGraph squareLoop(const std::vector<Pose2>& initial) {
  PoseGraph graph;
  for (const auto& p : initial) graph.addPose(p);
  graph.addEdge({0, 1, Pose2(2.0, 0.0, 0.0), kInformation, false});
  graph.addEdge({1, 2, Pose2(2.0, 0.0, M_PI / 2), kInformation, false});
  graph.addEdge({2, 3, Pose2(2.0, 0.0, M_PI / 2), kInformation, false});
  graph.addEdge({3, 4, Pose2(2.0, 0.0, M_PI / 2), kInformation, false});
  graph.addEdge({4, 1, Pose2(2.0, 0.0, M_PI / 2), kInformation, true});
  return graph;
}

const std::vector<Pose2> kOptimum = {Pose2(0, 0, 0), Pose2(2, 0, 0), Pose2(4, 0, M_PI / 2), Pose2(4, 2, M_PI),
                                     Pose2(2, 2, -M_PI / 2)};

}  // namespace

TEST(PoseGraph, SquareLoopConvergesToTheKnownOptimumFromWrongGuesses) {
  PoseGraph graph = squareLoop({Pose2(0.5, 0.0, 0.2), Pose2(2.3, 0.1, -0.2), Pose2(4.1, 0.1, M_PI / 2),
                                Pose2(4.0, 2.0, M_PI), Pose2(2.1, 2.1, -M_PI / 2)});
  graph.setPose(0, Pose2());  // the fixed first pose defines the frame
  const OptimisationSummary summary = graph.optimise();
  EXPECT_TRUE(summary.converged);
  for (size_t i = 0; i < kOptimum.size(); ++i) {
    EXPECT_NEAR(graph.poses()[i].x, kOptimum[i].x, 1e-6) << i;
    EXPECT_NEAR(graph.poses()[i].y, kOptimum[i].y, 1e-6) << i;
    EXPECT_NEAR(wrapAngle(graph.poses()[i].theta - kOptimum[i].theta), 0.0, 1e-6) << i;
  }
  EXPECT_LT(summary.final_cost, 1e-10);
}

TEST(PoseGraph, LoopClosureCorrectsDriftedOdometry) {
  // Odometry over-turns every corner by 0.03 rad; the loop edge says where pose 4 truly is relative to pose 0.
  PoseGraph graph;
  graph.addPose(Pose2());
  for (int i = 0; i < 4; ++i) {
    const Pose2 step(2.0, 0.0, i == 3 ? 0.0 : M_PI / 2 + 0.03);
    graph.addPose(graph.poses().back() * step);
    graph.addEdge({i, i + 1, step, kInformation, false});
  }
  const double drift_before = graph.poses().back().translation().norm();
  graph.addEdge({0, 4, Pose2(0.0, 0.0, 3 * M_PI / 2), Eigen::Vector3d(1e4, 1e4, 1e4).asDiagonal(), true});
  graph.optimise();
  EXPECT_GT(drift_before, 0.15);
  EXPECT_LT(graph.poses().back().translation().norm(), 0.01);
  EXPECT_NEAR(wrapAngle(graph.poses().back().theta - 3 * M_PI / 2), 0.0, 0.01);
}

TEST(PoseGraph, OneWrongLoopEdgeCannotBendTheMap) {
  // A straight corridor of 20 poses with exact odometry, and one wrong loop edge claiming pose 19 is
  // half a metre from where odometry puts it; the robust loss keeps the map within 5 mm.
  PoseGraph graph;
  graph.addPose(Pose2());
  for (int i = 1; i < 20; ++i) {
    graph.addPose(Pose2(0.1 * i, 0.0, 0.0));
    graph.addEdge({i - 1, i, Pose2(0.1, 0.0, 0.0), kInformation * 100.0, false});
  }
  graph.addEdge({0, 19, Pose2(1.9, 0.5, 0.3), kInformation * 100.0, true});
  graph.optimise();
  for (int i = 0; i < 20; ++i) {
    EXPECT_LT((graph.poses()[static_cast<size_t>(i)].translation() - Eigen::Vector2d(0.1 * i, 0.0)).norm(), 0.005) << i;
  }
  // Without the robust loss the same edge would bend it by centimetres: the loss is what protects.
  PoseGraph plain;
  plain.addPose(Pose2());
  for (int i = 1; i < 20; ++i) {
    plain.addPose(Pose2(0.1 * i, 0.0, 0.0));
    plain.addEdge({i - 1, i, Pose2(0.1, 0.0, 0.0), kInformation * 100.0, false});
  }
  plain.addEdge({0, 19, Pose2(1.9, 0.5, 0.3), kInformation * 100.0, false});
  plain.optimise();
  EXPECT_GT((plain.poses()[19].translation() - Eigen::Vector2d(1.9, 0.0)).norm(), 0.05);
}

TEST(PoseGraph, InformationFloorsTheStandardDeviation) {
  const Eigen::Matrix3d I = informationFrom(Eigen::Matrix3d::Identity() * 1e-12, 0.001, 0.002);
  EXPECT_NEAR(I(0, 0), 1.0 / (1e-6 + 1e-12), 1.0);
  EXPECT_NEAR(I(2, 2), 1.0 / (4e-6 + 1e-12), 1.0);
}

namespace {

/// A straight 1 m-step chain of `n` poses with exact odometry and a loop edge 2 -> n-2; poses from
/// `first_wrong` on start displaced. With `loop_first` the loop edge is added before the odometry.
PoseGraph chain(int n, int first_wrong, bool loop_first) {
  PoseGraph graph;
  for (int i = 0; i < n; ++i) graph.addPose(i < first_wrong ? Pose2(i, 0, 0) : Pose2(i + 0.2, 0.1 * (i % 3), 0.05 * i));
  const GraphEdge loop{2, n - 2, Pose2(n - 4, 0, 0), kInformation, true};
  if (loop_first) graph.addEdge(loop);
  for (int i = 0; i + 1 < n; ++i) graph.addEdge({i, i + 1, Pose2(1, 0, 0), kInformation, false});
  if (!loop_first) graph.addEdge(loop);
  return graph;
}

}  // namespace

TEST(PoseGraph, WindowedOptimisationMovesOnlyTheWindowAndReachesItsOptimum) {
  for (const bool loop_first : {false, true}) {  // edges in pose order (a SLAM run) or not
    PoseGraph graph = chain(12, 6, loop_first);
    const std::vector<Pose2> before = graph.poses();
    EXPECT_TRUE(graph.optimise(6).converged);
    for (int i = 0; i < 6; ++i) {  // held: bit for bit
      EXPECT_EQ(graph.poses()[size_t(i)].x, before[size_t(i)].x) << i;
      EXPECT_EQ(graph.poses()[size_t(i)].y, before[size_t(i)].y) << i;
      EXPECT_EQ(graph.poses()[size_t(i)].theta, before[size_t(i)].theta) << i;
    }
    for (int i = 6; i < 12; ++i) {  // the exact chain continues from the held poses
      EXPECT_NEAR(graph.poses()[size_t(i)].x, i, 1e-6) << i;
      EXPECT_NEAR(graph.poses()[size_t(i)].y, 0.0, 1e-6) << i;
      EXPECT_NEAR(wrapAngle(graph.poses()[size_t(i)].theta), 0.0, 1e-6) << i;
    }
  }
}

TEST(PoseGraph, WindowHoldsTheOldPosesThatTheWholeGraphWouldMove) {
  // Pose 3 starts displaced: the window (poses 6..) cannot fix it, the whole graph can.
  PoseGraph graph = chain(12, 12, false);
  graph.setPose(3, Pose2(3.0, 0.3, 0.0));
  graph.optimise(6);
  EXPECT_DOUBLE_EQ(graph.poses()[3].y, 0.3);
  graph.optimise();
  EXPECT_NEAR(graph.poses()[3].y, 0.0, 1e-6);
}
