// LoopCloser driven directly, so that the map's estimates and the frames' features can be set on purpose: what a
// relocalization adds to the graph (edges measured on their map keyframe's own features; on a floor that repeats,
// confirmed only by frames that see different ground) and the gate against features fixed to the camera.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/pipeline/FramePreparer.hpp"
#include "groundslam/pipeline/LoopClosure.hpp"
#include "groundslam/sim/Simulator.hpp"

using namespace groundslam;

namespace {

constexpr int kMapFrames = 150;   // frames 0-149 of the first lap make the map
constexpr int kLandingFrame = 210;  // the robot is carried to frame 210 of the second lap, over frame 10's ground
constexpr double kDegree = M_PI / 180.0;

std::shared_ptr<const Vocabulary> shippedVocabulary() {
  static const auto vocabulary =
      std::make_shared<const Vocabulary>(readVocabulary(std::string(GROUNDSLAM_SOURCE_DIR) + "/config/vocabulary/ground.gslmvoc"));
  return vocabulary;
}

/// An asphalt loop of 400 frames driven twice.
sim::SimulationSettings asphaltLoop() {
  sim::SimulationSettings s;
  s.texture_kind = "asphalt";
  s.path.kind = sim::PathKind::loop;
  s.path.frames = 400;
  s.path.seed = s.seed = 3;
  s.photometry.noise_sigma = 2.0;
  return s;
}

struct Relocalized {
  std::vector<LoopCandidate> edges;  ///< the joining edges, frame_a on the map, frame_b lost (closer indices)
  std::vector<int> simulated;        ///< closer index -> simulator frame
  std::vector<Pose2> estimates;      ///< closer index -> the estimate the closer was given
};

/// An asphalt loop driven twice. The first 150 frames make the map, with estimates whose heading drifts by
/// `bend_deg_per_frame` (an odometry heading bias), then tracking is lost and the robot lands on the second lap. Its
/// frames (odometry exact within the lost segment) are relocalized until the segment joins the map.
Relocalized relocalizeAfterACarry(const LocalizationSettings& localization, double bend_deg_per_frame, bool floor_repeats) {
  const sim::SequenceSimulator simulator(asphaltLoop());
  Config config;
  config.camera = cameraConfigOf(asphaltLoop().camera, asphaltLoop().mounting_height_m);
  config.localization = localization;
  const FramePreparer preparer(config);
  LoopCloser closer(config.loop_closure, shippedVocabulary(), config.matching, config.odometry, config.localization);
  if (floor_repeats) closer.floorRepeats();
  const auto& truth = simulator.groundTruth();
  Relocalized result;
  const Pose2 bend(0.0, 0.0, bend_deg_per_frame * kDegree);
  for (int k = 0; k < 400 - kLandingFrame + kMapFrames; ++k) {
    const int frame = k < kMapFrames ? k : k - kMapFrames + kLandingFrame;
    result.simulated.push_back(frame);
    if (k == 0) {
      result.estimates.push_back(truth[0]);
    } else if (k == kMapFrames) {
      closer.trackingLost(result.estimates);
      result.estimates.push_back(result.estimates.back() * Pose2(0.3, -0.2, 1.0));  // where the lost segment starts: unknown
    } else {
      const Pose2 step = between(truth[static_cast<size_t>(result.simulated[static_cast<size_t>(k) - 1])], truth[static_cast<size_t>(frame)]);
      result.estimates.push_back(result.estimates.back() * (k < kMapFrames ? step * bend : step));
    }
    const GroundFeatures features = preparer.prepare(simulator.renderFrame(frame), k).features;
    closer.process(k, k < kMapFrames ? kMapSegment : 1, features, result.estimates);
    if (k < kMapFrames) continue;
    result.edges = closer.relocalize(k, features, result.estimates);
    if (!result.edges.empty()) break;
  }
  return result;
}

/// How far each joining edge is from the true transform between its two frames: metres, degrees (the worst edge).
std::pair<double, double> worstEdgeError(const Relocalized& r, const sim::SequenceSimulator& simulator) {
  double worst_m = 0.0, worst_deg = 0.0;
  for (const LoopCandidate& edge : r.edges) {
    const Pose2 a = simulator.groundTruth()[static_cast<size_t>(r.simulated[static_cast<size_t>(edge.frame_a)])];
    const Pose2 b = simulator.groundTruth()[static_cast<size_t>(r.simulated[static_cast<size_t>(edge.frame_b)])];
    const Pose2 error = between(a, b).inverse() * edge.T_a_b;
    worst_m = std::max(worst_m, error.translation().norm());
    worst_deg = std::max(worst_deg, std::abs(error.theta) / kDegree);
  }
  return {worst_m, worst_deg};
}

}  // namespace

TEST(RelocalizationEdges, OnABentMapTheEdgeIsMeasuredOnItsKeyframeNotOnTheWholeMap) {
  // Heading drifting 0.2 degrees a frame: the map features around a place were stored by keyframes up to a footprint
  // behind it, turned by a degree or two against it. Localized on the whole map, the edge from the nearest keyframe
  // carries that turn; measured on the keyframe's own features, it does not.
  const sim::SequenceSimulator simulator(asphaltLoop());
  LocalizationSettings on_keyframe, on_map;
  on_map.measure_on_keyframe = false;
  const Relocalized measured = relocalizeAfterACarry(on_keyframe, 0.2, false);
  const Relocalized localized = relocalizeAfterACarry(on_map, 0.2, false);
  ASSERT_EQ(measured.edges.size(), 2u);
  ASSERT_EQ(localized.edges.size(), 2u);
  const auto [measured_m, measured_deg] = worstEdgeError(measured, simulator);
  const auto [localized_m, localized_deg] = worstEdgeError(localized, simulator);
  std::printf("worst joining edge: on the keyframe %.2f mm %.3f deg, on the whole map %.2f mm %.3f deg\n", 1000 * measured_m,
              measured_deg, 1000 * localized_m, localized_deg);
  EXPECT_LT(measured_m, 0.002);
  EXPECT_LT(measured_deg, 0.3);
  EXPECT_GT(localized_deg, 3.0 * measured_deg);  // the bend the whole map put into the edge
}

TEST(RelocalizationEdges, OnAFloorThatRepeatsTheConfirmingFramesSeeDifferentGround) {
  // Two localizations of nearly the same image confirm nothing a repetition could not: on a floor seen to repeat the
  // second comes from 5 cm on (localization.repeated_floor_baseline_m). Both joins are right; only the wait differs.
  const sim::SequenceSimulator simulator(asphaltLoop());
  LocalizationSettings any_baseline;
  any_baseline.repeated_floor_baseline_m = 0.0;
  const Relocalized waited = relocalizeAfterACarry(LocalizationSettings{}, 0.0, true);
  const Relocalized at_once = relocalizeAfterACarry(any_baseline, 0.0, true);
  const Relocalized not_repeating = relocalizeAfterACarry(LocalizationSettings{}, 0.0, false);
  ASSERT_EQ(waited.edges.size(), 2u);
  ASSERT_EQ(at_once.edges.size(), 2u);
  ASSERT_EQ(not_repeating.edges.size(), 2u);
  const auto apart = [](const Relocalized& r) {
    return between(r.estimates[static_cast<size_t>(r.edges[0].frame_b)], r.estimates[static_cast<size_t>(r.edges[1].frame_b)]).translation().norm();
  };
  std::printf("joined at closer frames %d (confirming frames %.1f cm apart) and %d (%.1f cm apart)\n", waited.edges[1].frame_b,
              100 * apart(waited), at_once.edges[1].frame_b, 100 * apart(at_once));
  EXPECT_GE(apart(waited), 0.05);
  EXPECT_LT(apart(at_once), 0.02);
  EXPECT_EQ(not_repeating.edges[1].frame_b, at_once.edges[1].frame_b);  // the baseline applies only where the floor repeats
  EXPECT_GT(waited.edges[1].frame_b, at_once.edges[1].frame_b);
  for (const Relocalized* r : {&waited, &at_once}) {
    const auto [m, deg] = worstEdgeError(*r, simulator);
    EXPECT_LT(m, 0.002);
    EXPECT_LT(deg, 0.3);
  }
}

namespace {

/// A loop candidate between frame 0 of an asphalt loop and a later frame whose features are frame 0's, each moved by
/// `T_0_later`'s inverse (the identity: every feature where it was in the image, as the robot's shadow, lens dirt or
/// bumper stay). The robot's estimate puts the later frame 1 cm from frame 0; in between it drove elsewhere. With
/// `unsure_frame`, the motion into that frame is marked as possibly a repetition off (LoopCloser::motionUnsure).
LoopCandidate candidateWithFrameZeroSeenAt(const Pose2& T_0_later, int unsure_frame = -1) {
  const sim::SequenceSimulator simulator(asphaltLoop());
  Config config;
  config.camera = cameraConfigOf(asphaltLoop().camera, asphaltLoop().mounting_height_m);
  const FramePreparer preparer(config);
  LoopCloser closer(config.loop_closure, shippedVocabulary(), config.matching, config.odometry, config.localization);
  const auto& truth = simulator.groundTruth();
  const GroundFeatures first = preparer.prepare(simulator.renderFrame(0), 0).features;
  const GroundFeatures elsewhere = preparer.prepare(simulator.renderFrame(100), 1).features;
  std::vector<Pose2> estimates = {truth[0]};
  if (unsure_frame == 0) closer.motionUnsure();
  closer.process(0, kMapSegment, first, estimates);
  const int later = config.loop_closure.database_delay_frames + 1;
  for (int k = 1; k < later; ++k) {
    estimates.push_back(truth[100]);
    if (unsure_frame == k) closer.motionUnsure();
    closer.process(k, kMapSegment, elsewhere, estimates);
  }
  GroundFeatures moved = first;
  for (Eigen::Vector2d& p : moved.points) p = T_0_later.inverse() * p;
  estimates.push_back(truth[0] * Pose2(0.01, 0.0, 0.0));
  if (unsure_frame == later) closer.motionUnsure();
  for (const LoopCandidate& c : closer.process(later, kMapSegment, moved, estimates)) {
    if (c.frame_a == 0) return c;
  }
  return {};
}

}  // namespace

TEST(LoopGates, AFitOnTheEarlierFramesOwnPoseIsRefusedAsStill) {
  const LoopCandidate still = candidateWithFrameZeroSeenAt(Pose2());
  EXPECT_EQ(still.frame_a, 0);
  EXPECT_EQ(still.rejected_by, LoopGate::still) << loopGateName(still.rejected_by);
  EXPECT_LT(still.T_a_b.translation().norm(), 1e-4);
  // 4 mm and 1.5 degrees off the earlier pose: outside localization.min_anchor_offset_* (3 mm, 1 degree), accepted.
  const Pose2 moved(0.004, 0.0, 1.5 * kDegree);
  const LoopCandidate revisit = candidateWithFrameZeroSeenAt(moved);
  EXPECT_TRUE(revisit.accepted()) << loopGateName(revisit.rejected_by);
  EXPECT_LT((revisit.T_a_b.translation() - moved.translation()).norm(), 1e-4);
  EXPECT_NEAR(revisit.T_a_b.theta, moved.theta, 1e-4);
  // Only the heading outside: 1 mm off and turned 1.5 degrees is a revisit too.
  EXPECT_TRUE(candidateWithFrameZeroSeenAt(Pose2(0.001, 0.0, 1.5 * kDegree)).accepted());
}

TEST(LoopGates, NoLoopClosureSpansAMotionThatMayBeARepetitionOff) {
  // The revisit of the test above (4 mm and 1.5 degrees from frame 0), accepted; with the motion into frame 2 or into
  // the later frame itself marked unsure, the map's estimate of the pair may be a tile off and the candidate is
  // refused as ambiguous before any matching. A motion before frame 0 (into frame 0 itself) is not between them.
  const Pose2 moved(0.004, 0.0, 1.5 * kDegree);
  ASSERT_TRUE(candidateWithFrameZeroSeenAt(moved).accepted());
  const int later = LoopClosureSettings{}.database_delay_frames + 1;
  for (int unsure : {2, later}) {
    const LoopCandidate refused = candidateWithFrameZeroSeenAt(moved, unsure);
    EXPECT_EQ(refused.frame_a, 0);
    EXPECT_EQ(refused.rejected_by, LoopGate::ambiguous) << unsure << ": " << loopGateName(refused.rejected_by);
    EXPECT_EQ(refused.matches, -1);
  }
  const LoopCandidate before = candidateWithFrameZeroSeenAt(moved, 0);
  EXPECT_TRUE(before.accepted()) << loopGateName(before.rejected_by);
}
