// Global localization with no pose prior: a map built from one simulated session, queried by another
// session (other path, other noise) over the same ground.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <cstdio>

#include <gtest/gtest.h>

#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/io/MapFile.hpp"
#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/pipeline/Slam.hpp"
#include "groundslam/localization/GlobalLocalizer.hpp"
#include "groundslam/pipeline/FramePreparer.hpp"
#include "groundslam/sim/Simulator.hpp"
#include "OutdoorLook.hpp"

using namespace groundslam;

namespace {

std::shared_ptr<const Vocabulary> shippedVocabulary() {
  static const auto vocabulary =
      std::make_shared<const Vocabulary>(readVocabulary(std::string(GROUNDSLAM_SOURCE_DIR) + "/config/vocabulary/ground.gslmvoc"));
  return vocabulary;
}

sim::SimulationSettings session(const std::string& texture, sim::PathKind path, int frames, std::uint64_t seed) {
  sim::SimulationSettings s;
  s.texture_kind = texture;
  s.path.kind = path;
  s.path.frames = frames;
  s.path.seed = seed;
  s.seed = seed;
  s.ground_seed = 11;
  s.ground_size_m = 1.6;
  s.photometry.noise_sigma = 2.0;
  return s;
}

/// A 400-frame carpet loop under the outdoor look: a shadow turning with the heading, lens dirt, glare, a bumper,
/// a rocking and bouncing mount, motion and defocus blur, noise, exposure changes, vignetting, wet from 60%.
sim::SimulationSettings carpetLoopUnderTheOutdoorLook(std::uint64_t seed) {
  sim::SimulationSettings s;
  s.texture_kind = "carpet";
  s.path.kind = sim::PathKind::loop;
  s.path.frames = 400;
  s.path.seed = s.seed = seed;
  groundslam::testing::putUnderTheOutdoorLook(s);
  return s;
}

Config configFor(const sim::SimulationSettings& s) {
  Config c;
  c.camera = cameraConfigOf(s.camera, s.mounting_height_m);
  return c;
}

/// A map from a session's frames at their true poses, one keyframe every `spacing` frames.
FeatureMap mapOf(const sim::SequenceSimulator& simulator, const FramePreparer& preparer, int spacing) {
  FeatureMap map(shippedVocabulary());
  for (int i = 0; i < simulator.frameCount(); i += spacing) {
    map.addAnchor(i, simulator.groundTruth()[static_cast<size_t>(i)], 0, preparer.prepare(simulator.renderFrame(i), i).features);
  }
  return map;
}

struct Score {
  int on_map = 0;      ///< query frames within 5 cm of a map keyframe
  int localized = 0;   ///< of those, localized within 1 cm and 1 degree
  int wrong = 0;       ///< localized anywhere more than 5 cm or 2 degrees off
  double total_ms = 0.0;
  int tried = 0;
};

Score localizeSession(const FeatureMap& map, const sim::SequenceSimulator& queries, const FramePreparer& preparer, int step,
                      const Config& config) {
  Score score;
  const LocalizationSettings settings;
  for (int i = 0; i < queries.frameCount(); i += step) {
    const GroundFeatures features = preparer.prepare(queries.renderFrame(i), i).features;
    const auto start = std::chrono::steady_clock::now();
    const Localization l = localizeGlobally(map, features, settings, config.odometry);
    score.total_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    ++score.tried;
    const Pose2 truth = queries.groundTruth()[static_cast<size_t>(i)];
    double nearest = 1e9;
    for (const auto& a : map.anchors()) nearest = std::min(nearest, (a.T_map_anchor.translation() - truth.translation()).norm());
    const double e_t = (l.T_map_robot.translation() - truth.translation()).norm();
    const double e_r = std::abs(wrapAngle(l.T_map_robot.theta - truth.theta)) * 180.0 / M_PI;
    if (nearest < 0.05) ++score.on_map;
    if (l.ok() && e_t < 0.01 && e_r < 1.0 && nearest < 0.05) ++score.localized;
    if (l.ok() && (e_t > 0.05 || e_r > 2.0)) ++score.wrong;
  }
  return score;
}

Score secondSession(const std::string& texture) {
  auto mapping = session(texture, sim::PathKind::lawnmower, 500, 1);
  mapping.path.lane_length_m = 0.5;
  const sim::SequenceSimulator first(mapping);
  const FramePreparer preparer(configFor(mapping));
  const FeatureMap map = mapOf(first, preparer, 3);
  auto second_settings = session(texture, sim::PathKind::random_walk, 200, 2);
  second_settings.path.area_m = 0.4;
  const sim::SequenceSimulator second(second_settings);
  const Score s = localizeSession(map, second, preparer, 5, configFor(mapping));
  std::printf("%s: map of %zu features (%.1f B each); %d of %d query frames on mapped ground, %d localized there, %d wrong; "
              "%.1f ms per localization\n", texture.c_str(), map.features().size(), double(map.bytes()) / double(map.features().size()),
              s.on_map, s.tried, s.localized, s.wrong, s.total_ms / s.tried);
  return s;
}

}  // namespace

TEST(GlobalLocalization, ASecondSessionLocalizesOnTheFirstSessionsMap) {
  const Score s = secondSession("asphalt");
  ASSERT_GE(s.on_map, 15);
  EXPECT_GE(s.localized, 0.95 * s.on_map);
  EXPECT_EQ(s.wrong, 0);
}

TEST(GlobalLocalization, TilesAreRefusedRatherThanLocalizedOneTileOff) {
  // Every tile carries the same pattern: the pose one tile over is confirmed as well as the true one, so
  // with no prior the localizer must refuse, never pick a repetition.
  const Score s = secondSession("tiles");
  EXPECT_EQ(s.wrong, 0);
}

namespace {

std::string mapErrorOf(const std::string& name) {
  try {
    readMap(std::string(GROUNDSLAM_SOURCE_DIR) + "/tests/data/map/" + name + ".gsmap", shippedVocabulary());
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(MapFile, RoundTripsExactly) {
  const auto settings = session("asphalt", sim::PathKind::loop, 30, 1);
  const sim::SequenceSimulator simulator(settings);
  const FramePreparer preparer(configFor(settings));
  const FeatureMap map = mapOf(simulator, preparer, 5);
  const FeatureMap back = parseMap(formatMap(map, 0), "memory", shippedVocabulary());
  ASSERT_EQ(back.anchors().size(), map.anchors().size());
  ASSERT_EQ(back.features().size(), map.features().size());
  for (size_t a = 0; a < map.anchors().size(); ++a) {
    EXPECT_EQ(back.anchors()[a].frame, map.anchors()[a].frame);
    EXPECT_EQ(back.anchors()[a].T_map_anchor.x, map.anchors()[a].T_map_anchor.x);
    EXPECT_EQ(back.anchors()[a].T_map_anchor.theta, map.anchors()[a].T_map_anchor.theta);
  }
  for (size_t i = 0; i < map.features().size(); ++i) {
    EXPECT_EQ(back.features()[i].descriptor, map.features()[i].descriptor);
    EXPECT_EQ(back.features()[i].point, map.features()[i].point);
    EXPECT_EQ(back.features()[i].angle_rad, map.features()[i].angle_rad);
    EXPECT_EQ(back.features()[i].anchor, map.features()[i].anchor);
    EXPECT_EQ(back.features()[i].octave, map.features()[i].octave);
  }
  EXPECT_EQ(formatMap(back, 0), formatMap(map, 0));
  EXPECT_EQ(formatMap(map, 0).size(), 20 + 32 * map.anchors().size() + 49 * map.features().size() + 8);
}

TEST(MapFile, CorruptAndCraftedFilesAreRefusedWithTheReason) {
  EXPECT_NE(mapErrorOf("truncated").find("truncated.gsmap: map file is"), std::string::npos);
  EXPECT_NE(mapErrorOf("bad_checksum").find("bad_checksum.gsmap: map file is corrupt (checksum)"), std::string::npos);
  EXPECT_NE(mapErrorOf("feature_anchor_out_of_range").find("map file is inconsistent: feature 0 names keyframe 10 of 5"), std::string::npos)
      << mapErrorOf("feature_anchor_out_of_range");
  EXPECT_NE(mapErrorOf("nan_keyframe_pose").find("keyframe 0 has a pose that is not finite"), std::string::npos);
  EXPECT_NE(mapErrorOf("inf_feature_position").find("feature 0 has a position"), std::string::npos);
  EXPECT_NE(mapErrorOf("future_version").find("map format version 9"), std::string::npos);
  EXPECT_NE(mapErrorOf("huge_anchor_count").find("its header promises"), std::string::npos);
  EXPECT_NE(mapErrorOf("empty").find("holds no keyframes or no features"), std::string::npos);
  EXPECT_EQ(mapErrorOf("valid_tiny"), "");
}

TEST(Relocalization, AKidnappedRobotRelocalizesAndTheGapSnapsIntoPlace) {
  // A loop driven twice; frames 250-329 are never seen (the robot is carried 80 cm along its path).
  auto settings = session("asphalt", sim::PathKind::loop, 400, 3);
  settings.ground_seed.reset();
  settings.mount_jitter_deg = 0.5;
  const sim::SequenceSimulator simulator(settings);
  Config config = configFor(settings);
  Slam slam(config, shippedVocabulary());
  Trajectory truth;
  int relocalized_at = -1, lost = 0;
  std::string landing_status;  // frame 330's, the first after the gap
  std::vector<int> processed;  // the simulator's frame of each frame Slam saw
  for (int i = 0; i < simulator.frameCount(); ++i) {
    if (i >= 250 && i < 330) continue;
    processed.push_back(i);
    const FrameResult r = slam.process(simulator.renderFrame(i), static_cast<double>(i));
    truth.push_back({static_cast<double>(i), simulator.groundTruth()[static_cast<size_t>(i)]});
    if (i == 330) landing_status = r.statusName();
    lost += r.status == FrameStatus::lost ? 1 : 0;
    if (r.status == FrameStatus::relocalized && relocalized_at < 0) relocalized_at = i;
  }
  slam.finish();
  EXPECT_GE(lost, 1);
  // The frame that lost tracking says why (its images do not overlap: no matches survive the ratio test).
  EXPECT_EQ(landing_status.rfind("lost_too_few_", 0), 0u) << landing_status;
  ASSERT_GE(relocalized_at, 330);
  EXPECT_LE(relocalized_at, 335);  // within 5 frames of landing on mapped ground
  // relocalizations.csv's record: each lost frame's localization; the last joined the map, at the frame that said
  // relocalized, where the truth is (the map frame is the first pose's).
  const std::vector<RelocalizationAttempt>& attempts = slam.relocalizationAttempts();
  ASSERT_FALSE(attempts.empty());
  for (const RelocalizationAttempt& a : attempts) EXPECT_GE(processed.at(static_cast<size_t>(a.frame)), 330);
  const RelocalizationAttempt& last = attempts.back();
  EXPECT_EQ(last.outcome, RelocalizationOutcome::joined);
  EXPECT_EQ(last.localization.status, LocalizationStatus::localized);
  const int last_frame = processed.at(static_cast<size_t>(last.frame));
  EXPECT_EQ(last_frame, relocalized_at);
  const Pose2 true_pose = between(simulator.groundTruth()[0], simulator.groundTruth()[static_cast<size_t>(last_frame)]);
  EXPECT_LT((last.localization.T_map_robot.translation() - true_pose.translation()).norm(), 0.01);
  EXPECT_LT(std::abs(wrapAngle(last.localization.T_map_robot.theta - true_pose.theta)), 1.0 * M_PI / 180.0);
  const TrajectoryMetrics m = evaluateTrajectory(truth, slam.trajectory()).metrics;
  EXPECT_EQ(m.measured_frames, m.groundtruth_frames);
  EXPECT_LT(m.ate_rmse_m, 0.005);
  EXPECT_LT(m.rotation_mae_deg, 0.2);
}

TEST(Relocalization, AfterABlankFrameTheGroundSeenJustBeforeFindsTheRobot) {
  // New ground all along (half a lap), and one blank frame (a covered lens): tracking is lost, and the robot
  // is still over the ground of the 20 frames before, which are not yet places (the paper's delay). Global
  // localization alone: the bridge to the last tracked frame (odometry.bridge_max_frames) is off.
  auto settings = session("asphalt", sim::PathKind::loop, 400, 5);
  settings.ground_seed.reset();
  const sim::SequenceSimulator simulator(settings);
  Config config = configFor(settings);
  config.odometry_checks.bridge_max_frames = 0;
  Slam slam(config, shippedVocabulary());
  Trajectory truth;
  int relocalized_at = -1, lost = 0;
  for (int i = 0; i < 200; ++i) {
    const cv::Mat image = i == 120 ? cv::Mat(simulator.renderFrame(i).size(), CV_8U, cv::Scalar(128)) : simulator.renderFrame(i);
    const FrameResult r = slam.process(image, static_cast<double>(i));
    if (i != 120) truth.push_back({static_cast<double>(i), simulator.groundTruth()[static_cast<size_t>(i)]});
    lost += r.status == FrameStatus::lost ? 1 : 0;
    if (r.status == FrameStatus::relocalized && relocalized_at < 0) relocalized_at = i;
  }
  slam.finish();
  // Frame 120 fails, and so does 121's odometry against it; 121 and 122 localize on frames 100-119 and agree.
  EXPECT_GE(lost, 1);
  EXPECT_GE(relocalized_at, 121);
  EXPECT_LE(relocalized_at, 124);
  const TrajectoryMetrics m = evaluateTrajectory(truth, slam.trajectory()).metrics;
  EXPECT_LT(m.ate_rmse_m, 0.003);
}

TEST(Relocalization, AfterABlankFrameTheNextIsMeasuredAgainstTheLastTrackedFrame) {
  // The same blank frame 120, with the images' alignment off: frame 121 cannot be measured against frame 120, but
  // its features fit frame 119's (two steps back), and that joins the lost segment at once. The joined motion is the
  // true one within half a millimetre and 0.05 degrees, and the trajectory is as good as global localization's.
  auto settings = session("asphalt", sim::PathKind::loop, 400, 5);
  settings.ground_seed.reset();
  const sim::SequenceSimulator simulator(settings);
  Config config = configFor(settings);
  config.odometry_checks.align_images = false;
  Slam slam(config, shippedVocabulary());
  Trajectory truth;
  std::vector<FrameStatus> status;
  for (int i = 0; i < 140; ++i) {
    const cv::Mat image = i == 120 ? cv::Mat(simulator.renderFrame(i).size(), CV_8U, cv::Scalar(128)) : simulator.renderFrame(i);
    status.push_back(slam.process(image, static_cast<double>(i)).status);
    if (i != 120) truth.push_back({static_cast<double>(i), simulator.groundTruth()[static_cast<size_t>(i)]});
  }
  slam.finish();
  EXPECT_EQ(status[120], FrameStatus::lost);
  EXPECT_EQ(status[121], FrameStatus::relocalized);
  for (int i = 122; i < 140; ++i) EXPECT_EQ(status[size_t(i)], FrameStatus::ok) << i;
  const Trajectory estimated = slam.trajectory();
  const Pose2 joined = between(estimated[119].T_world_robot, estimated[121].T_world_robot);
  const Pose2 true_motion = between(simulator.groundTruth()[119], simulator.groundTruth()[121]);
  EXPECT_LT((joined.translation() - true_motion.translation()).norm(), 0.0005);
  EXPECT_LT(std::abs(wrapAngle(joined.theta - true_motion.theta)), 0.05 * M_PI / 180.0);
  const TrajectoryMetrics m = evaluateTrajectory(truth, estimated).metrics;
  EXPECT_LT(m.ate_rmse_m, 0.003);
}

TEST(Relocalization, AfterABlankFrameImagesThatStayStillAreNotTakenForRestButAStandingRobotIsBridged) {
  // The same blank frame 120. Then frames 121-124 show frame 119's image again, as the robot's shadow, lens dirt and
  // bumper would on a floor too smooth to show its own motion: nothing joins the robot to the map at rest there, and
  // it is found once it shows new ground. A robot that really stood still (frames 100-139 all show frame 100's
  // ground) is joined within two frames, as before bridges that put the robot back on the last tracked pose were
  // refused (Slam::backOnTheTrackedPose). Measured: both runs give the same statuses without that rule, which the
  // moving run's identical images do not reach; the test guards that the rule leaves a robot that stood still found.
  auto settings = session("asphalt", sim::PathKind::loop, 400, 5);
  settings.ground_seed.reset();
  const sim::SequenceSimulator simulator(settings);
  Config config = configFor(settings);
  config.odometry_checks.align_images = false;
  const cv::Mat blank(simulator.renderFrame(0).size(), CV_8U, cv::Scalar(128));
  const auto run = [&](const std::function<int(int)>& shown) {
    Slam slam(config, shippedVocabulary());
    std::vector<FrameStatus> status;
    for (int i = 0; i < 140; ++i) status.push_back(slam.process(i == 120 ? blank : simulator.renderFrame(shown(i)), i).status);
    slam.finish();
    return std::make_pair(status, slam.trajectory());
  };
  const auto [moving, moving_trajectory] = run([](int i) { return i >= 121 && i <= 124 ? 119 : i; });
  EXPECT_EQ(moving[120], FrameStatus::lost);
  for (int i = 121; i <= 124; ++i) EXPECT_NE(moving[size_t(i)], FrameStatus::relocalized) << i;
  const auto found = std::find(moving.begin() + 125, moving.end(), FrameStatus::relocalized);
  ASSERT_NE(found, moving.end());
  const Pose2 joined = between(moving_trajectory[119].T_world_robot, moving_trajectory[139].T_world_robot);
  const Pose2 true_motion = between(simulator.groundTruth()[119], simulator.groundTruth()[139]);
  EXPECT_LT((joined.translation() - true_motion.translation()).norm(), 0.001);
  const auto [resting, resting_trajectory] = run([](int i) { return std::min(i, 100); });
  EXPECT_EQ(resting[120], FrameStatus::lost);
  EXPECT_TRUE(resting[121] == FrameStatus::relocalized || resting[122] == FrameStatus::relocalized);  // as without the rule
  EXPECT_LT(between(resting_trajectory[100].T_world_robot, resting_trajectory[139].T_world_robot).translation().norm(), 0.0005);
}

TEST(Relocalization, AMotionRefusedForItsSpeedIsBridgedToTheLastTrackedFrame) {
  // Three frames dropped without a trace in the timestamps, 0.9 cm steps: the motion across them, 3.6 cm in one
  // frame's time, is 2.7 cm off the robot's speed (allowed: 2 cm + 50% of a step) and is refused, not every match
  // agreeing with it (decisive_inlier_share set out of reach) and the robot's steps not asked (repetition_max_steps
  // 0; on carpet under the outdoor look such a fit was 5 mm off four steps). The next frame is bridged to the last
  // tracked one: 4.5 cm in two frames' time is within 2 cm + 50% of two steps, and its fit has what a loop closure
  // needs. Global localization is kept out (localization.min_votes out of reach: a weak floor where it finds nothing, as carpet
  // under the outdoor look), and so are the map's places near the lost frames (loop_closure.lost_reach_m 0): with the
  // bridge off the robot stays lost.
  auto settings = session("asphalt", sim::PathKind::loop, 400, 5);
  settings.ground_seed.reset();
  settings.path.step_m = 0.009;
  const sim::SequenceSimulator simulator(settings);
  const std::vector<int> shown = [] {
    std::vector<int> frames;
    for (int i = 0; i < 135; ++i) {
      if (i < 121 || i > 123) frames.push_back(i);  // 121-123 dropped
    }
    return frames;
  }();
  const auto run = [&](int bridge_max_frames, std::vector<FrameResult>& results) {
    Config config = configFor(settings);
    config.odometry_checks.decisive_inlier_share = 1.5;
    config.odometry_checks.repetition_max_steps = 0;
    config.localization.min_votes = 1e8;
    config.loop_closure.lost_reach_m = 0.0;
    config.odometry_checks.bridge_max_frames = bridge_max_frames;
    Slam slam(config, shippedVocabulary());
    for (size_t k = 0; k < shown.size(); ++k) results.push_back(slam.process(simulator.renderFrame(shown[k]), static_cast<double>(k)));
    slam.finish();
    return slam.trajectory();
  };
  std::vector<FrameResult> bridged, unbridged;
  const Trajectory estimated = run(3, bridged);
  run(0, unbridged);
  // Position 121 shows frame 124, position 122 frame 125.
  EXPECT_EQ(bridged[121].status, FrameStatus::lost);
  EXPECT_EQ(bridged[121].fallback_reason, FitStatus::implausible_motion);
  EXPECT_EQ(bridged[122].status, FrameStatus::relocalized);
  const Pose2 joined = between(estimated[120].T_world_robot, estimated[122].T_world_robot);
  const Pose2 true_motion = between(simulator.groundTruth()[120], simulator.groundTruth()[125]);
  EXPECT_LT((joined.translation() - true_motion.translation()).norm(), 0.001);
  EXPECT_LT(std::abs(wrapAngle(joined.theta - true_motion.theta)), 0.1 * M_PI / 180.0);
  for (size_t k = 123; k < shown.size(); ++k) EXPECT_EQ(bridged[k].status, FrameStatus::ok) << k;
  for (size_t k = 122; k < shown.size(); ++k) EXPECT_EQ(unbridged[k].status, FrameStatus::lost) << k;
}

TEST(Relocalization, WhichLossesMayBeBridged) {
  // Too little evidence, or everything left in place: bridged unless the fits show a rival repetition.
  for (FitStatus failed : {FitStatus::too_few_matches, FitStatus::too_few_inliers, FitStatus::degenerate, FitStatus::still}) {
    EXPECT_TRUE(bridgeableLoss(failed, false, false)) << fitStatusName(failed);
    EXPECT_TRUE(bridgeableLoss(failed, false, true)) << fitStatusName(failed);
    EXPECT_FALSE(bridgeableLoss(failed, true, false)) << fitStatusName(failed);
  }
  // The robot's speed (frames dropped without a trace) and a rival: only where neither fits nor images show a repetition.
  for (FitStatus failed : {FitStatus::implausible_motion, FitStatus::ambiguous}) {
    EXPECT_TRUE(bridgeableLoss(failed, false, false)) << fitStatusName(failed);
    EXPECT_FALSE(bridgeableLoss(failed, false, true)) << fitStatusName(failed);
    EXPECT_FALSE(bridgeableLoss(failed, true, false)) << fitStatusName(failed);
  }
  EXPECT_FALSE(bridgeableLoss(FitStatus::solver_failed, false, false));
}

TEST(Relocalization, AWeakBridgeIsBelievedWhereItAgreesWithTheLostSegment) {
  // Frame 120 is blank: tracking is lost for too few matches and frames 120-121 are placed by the robot's steps, which
  // on a loop at an even speed put frame 121 within a millimetre of the truth. Frame 121's features against frame
  // 119's are a bridge too weak for a loop closure here (loop_closure.min_inliers set out of reach): believed only
  // because the fit agrees with the lost segment's own estimate (odometry.bridge_corroboration_*). Image alignment, the
  // motion search, global localization and the map's places near the robot are kept out, so nothing else joins it.
  auto settings = session("asphalt", sim::PathKind::loop, 400, 5);
  settings.ground_seed.reset();
  const sim::SequenceSimulator simulator(settings);
  const cv::Mat blank(simulator.renderFrame(0).size(), CV_8U, cv::Scalar(128));
  const auto run = [&](int min_inliers, double agreement_m, double agreement_deg, std::vector<FrameStatus>& status) {
    Config config = configFor(settings);
    config.loop_closure.min_inliers = 100000;
    config.odometry_checks.align_images = false;
    config.odometry_checks.bridge_search_turn_deg = 0.0;
    config.odometry_checks.bridge_spectral_min_peak = 0.0;
    config.localization.min_votes = 1e8;
    config.loop_closure.lost_reach_m = 0.0;
    config.odometry_checks.bridge_corroborated_min_inliers = min_inliers;
    config.odometry_checks.bridge_corroboration_m = agreement_m;
    config.odometry_checks.bridge_corroboration_deg = agreement_deg;
    Slam slam(config, shippedVocabulary());
    for (int i = 0; i < 130; ++i) status.push_back(slam.process(i == 120 ? blank : simulator.renderFrame(i), i).status);
    slam.finish();
    return slam.trajectory();
  };
  std::vector<FrameStatus> corroborated, off, disagreeing, turned, too_weak;
  const Trajectory estimated = run(8, 0.003, 0.6, corroborated);
  run(0, 0.003, 0.6, off);
  run(8, 1e-6, 0.6, disagreeing);
  run(8, 0.003, 1e-6, turned);
  run(100000, 0.003, 0.6, too_weak);  // more inliers asked than the fit has
  EXPECT_EQ(corroborated[120], FrameStatus::lost);
  EXPECT_EQ(corroborated[121], FrameStatus::relocalized);
  for (int i = 122; i < 130; ++i) EXPECT_EQ(corroborated[size_t(i)], FrameStatus::ok) << i;
  const Pose2 joined = between(estimated[119].T_world_robot, estimated[121].T_world_robot);
  const Pose2 true_motion = between(simulator.groundTruth()[119], simulator.groundTruth()[121]);
  EXPECT_LT((joined.translation() - true_motion.translation()).norm(), 0.0005);
  EXPECT_LT(std::abs(wrapAngle(joined.theta - true_motion.theta)), 0.05 * M_PI / 180.0);
  for (int i = 121; i < 130; ++i) {
    EXPECT_EQ(off[size_t(i)], FrameStatus::lost) << i;
    EXPECT_EQ(disagreeing[size_t(i)], FrameStatus::lost) << i;
    EXPECT_EQ(turned[size_t(i)], FrameStatus::lost) << i;
    EXPECT_EQ(too_weak[size_t(i)], FrameStatus::lost) << i;
  }
}

TEST(Relocalization, ALossInsideALostSegmentIsBridgedToThatSegmentNotLeftAdrift) {
  // Carried 80 cm away (frames 250-329 never seen) with global localization kept out (a weak floor where it finds
  // nothing), and the map's places near the lost frames too (loop_closure.lost_reach_m 0): from frame 330 the robot
  // is lost, its segment measured by odometry. Then a blank frame (340) and two
  // frames dropped (341, 342): frame 343 cannot be measured against the blank one, and is measured against frame
  // 339 of the lost segment instead, which the new segment then continues. Without the bridge (bridge_max_frames 0)
  // the motion 339 -> 343 is a guess, one usual step a frame shown: two steps short.
  auto settings = session("asphalt", sim::PathKind::loop, 400, 3);
  settings.ground_seed.reset();
  const sim::SequenceSimulator simulator(settings);
  std::vector<int> shown;
  for (int i = 0; i < 360; ++i) {
    if (i < 250 || (i >= 330 && i != 341 && i != 342)) shown.push_back(i);
  }
  const auto run = [&](int bridge_max_frames, std::vector<FrameResult>& results) {
    Config config = configFor(settings);
    config.localization.min_votes = 1e8;
    config.loop_closure.lost_reach_m = 0.0;
    config.odometry_checks.bridge_max_frames = bridge_max_frames;
    Slam slam(config, shippedVocabulary());
    for (const int i : shown) {
      const cv::Mat image = i == 340 ? cv::Mat(simulator.renderFrame(i).size(), CV_8U, cv::Scalar(128)) : simulator.renderFrame(i);
      results.push_back(slam.process(image, static_cast<double>(i)));
    }
    slam.finish();
    return slam.trajectory();
  };
  std::vector<FrameResult> bridged, unbridged;
  const Trajectory estimated = run(3, bridged);
  const Trajectory guessed = run(0, unbridged);
  const size_t at339 = 259, at343 = 261;  // positions in `shown`
  ASSERT_EQ(shown[at339], 339);
  ASSERT_EQ(shown[at343], 343);
  // Lost all along: the segment continued is not the map.
  for (size_t k = 250; k < shown.size(); ++k) EXPECT_EQ(bridged[k].status, FrameStatus::lost) << shown[k];
  const Pose2 true_motion = between(simulator.groundTruth()[339], simulator.groundTruth()[343]);
  const Pose2 joined = between(estimated[at339].T_world_robot, estimated[at343].T_world_robot);
  EXPECT_LT((joined.translation() - true_motion.translation()).norm(), 0.0005);
  EXPECT_LT(std::abs(wrapAngle(joined.theta - true_motion.theta)), 0.05 * M_PI / 180.0);
  const Pose2 guess = between(guessed[at339].T_world_robot, guessed[at343].T_world_robot);
  EXPECT_GT((guess.translation() - true_motion.translation()).norm(), 0.015);
}

TEST(Relocalization, ASegmentLostAgainBeforeItWasFoundJoinsWithTheNextOne) {
  // A loop driven twice. Carried 30 cm ahead onto ground not yet mapped (frames 100-129 never seen), the robot is
  // lost from frame 130; a blank frame at 140 loses it again (no bridge: bridge_max_frames 0). The second segment
  // is relocalized when the robot comes back onto the first lap's ground (frame 200 on); the first, frames
  // 130-139, is found then on the second segment's ground and joins too, instead of staying where its guess put it
  // (one step past frame 99: 29 cm short).
  auto settings = session("asphalt", sim::PathKind::loop, 400, 3);
  settings.ground_seed.reset();
  const sim::SequenceSimulator simulator(settings);
  Config config = configFor(settings);
  config.odometry_checks.bridge_max_frames = 0;
  Slam slam(config, shippedVocabulary());
  Trajectory truth;
  std::vector<FrameStatus> status;
  for (int i = 0; i < 240; ++i) {
    if (i >= 100 && i < 130) continue;
    const cv::Mat image = i == 140 ? cv::Mat(simulator.renderFrame(i).size(), CV_8U, cv::Scalar(128)) : simulator.renderFrame(i);
    status.push_back(slam.process(image, static_cast<double>(i)).status);
    if (i != 140) truth.push_back({static_cast<double>(i), simulator.groundTruth()[static_cast<size_t>(i)]});
  }
  slam.finish();
  EXPECT_EQ(status[100], FrameStatus::lost);  // frame 130
  const Trajectory estimated = slam.trajectory();
  const TrajectoryMetrics m = evaluateTrajectory(truth, estimated).metrics;  // paired by time: not the blank frame
  EXPECT_EQ(m.measured_frames, m.groundtruth_frames);  // frames 130-139 too
  EXPECT_LT(m.ate_rmse_m, 0.005);
  // Frames 130 -> 139 against frame 99: placed, not guessed.
  const Pose2 placed = between(estimated[99].T_world_robot, estimated[109].T_world_robot);
  const Pose2 true_motion = between(simulator.groundTruth()[99], simulator.groundTruth()[139]);
  EXPECT_LT((placed.translation() - true_motion.translation()).norm(), 0.005);
}

namespace {

/// The quarter turn of the next two tests: the carpet loop under the outdoor look with a turn on the spot every 80
/// frames, frame 3 dropped; its first 46 frames run with a configuration `tweak` has changed.
struct QuarterTurnOnCarpet {
  static sim::SimulationSettings settings() {
    sim::SimulationSettings s = carpetLoopUnderTheOutdoorLook(23);
    s.motion.spin_every = 80;
    return s;
  }
  static int image(int position) { return position < 3 ? position : position + 1; }  // frame 3 dropped
  /// The true motion between two of the run's frames.
  Pose2 trueMotion(int from, int to) const {
    return between(simulator.groundTruth()[size_t(image(from))], simulator.groundTruth()[size_t(image(to))]);
  }
  Trajectory run(const std::function<void(Config&)>& tweak, std::vector<FrameStatus>& status) const {
    Config config = configFor(s);
    tweak(config);
    Slam slam(config, shippedVocabulary());
    for (int k = 0; k < 46; ++k) status.push_back(slam.process(simulator.renderFrame(image(k)), k).status);
    slam.finish();
    return slam.trajectory();
  }
  const sim::SimulationSettings s = settings();
  const sim::SequenceSimulator simulator{s};
};

}  // namespace

TEST(Relocalization, AQuarterTurnLostOnCarpetUnderTheOutdoorLookIsFoundBySearchingTheTurns) {
  // Carpet with the outdoor look (a shadow turning with the heading, lens dirt, glare, a bumper, a rocking mount,
  // motion blur); frame 3 dropped. Frame 39 turns 91.8 degrees on the spot: brute-force matching keeps 12 pairs
  // and the frame is lost. Searching the turns every 5 degrees after one usual step finds it at frames 39 and 40
  // alike (carried by odometry), so frame 40 joins the map and frame 39 falls into place with it. With the search off
  // the robot stays lost; its segment still turns by the quarter turn the images' spectra measured at frame 39
  // (odometry.fallback_turn_image_width_px). Without those too, it stays a quarter turn off.
  const QuarterTurnOnCarpet quarter_turn;
  const auto run = [&](double search_turn_deg, std::vector<FrameStatus>& status, int spectra_width_px = 320) {
    return quarter_turn.run(
        [&](Config& config) {
          config.odometry_checks.bridge_search_turn_deg = search_turn_deg;
          config.odometry_checks.bridge_spectral_min_peak = 0.0;  // the search alone (the spectra's own bridge: below)
          config.fallback.turn_image_width_px = spectra_width_px;
        },
        status);
  };
  std::vector<FrameStatus> searched, unsearched;
  const Trajectory found = run(5.0, searched);
  const Trajectory lost = run(0.0, unsearched);
  const Pose2 true_motion = quarter_turn.trueMotion(38, 45);
  EXPECT_NEAR(true_motion.theta, 102.2 * M_PI / 180.0, 0.1 * M_PI / 180.0);  // the quarter turn and the circle
  EXPECT_EQ(searched[39], FrameStatus::lost);
  EXPECT_EQ(searched[40], FrameStatus::relocalized);
  for (size_t k = 41; k < searched.size(); ++k) EXPECT_NE(searched[k], FrameStatus::lost) << k;
  // The lost frame itself sits where the truth puts it too (its odometry to frame 40 carries the bridge back).
  const Pose2 turned = between(found[38].T_world_robot, found[39].T_world_robot);
  const Pose2 true_turn = quarter_turn.trueMotion(38, 39);
  EXPECT_LT((turned.translation() - true_turn.translation()).norm(), 0.008);
  // Measured 0.29 degrees, and 0.34 since the headings are refined outdoors (session 30; the joined motion below went
  // 0.38 -> 0.43 degrees with it).
  EXPECT_LT(std::abs(wrapAngle(turned.theta - true_turn.theta)), 0.4 * M_PI / 180.0);
  const Pose2 joined = between(found[38].T_world_robot, found[45].T_world_robot);
  EXPECT_LT((joined.translation() - true_motion.translation()).norm(), 0.008);
  // Measured 0.12 degrees until session 20 and 0.39 since points are tracked through the artifacts (docs/accuracy.md,
  // Session 21): the frame after the loss ties its tilt precisely to a previous mount that was not estimated. Left open.
  EXPECT_LT(std::abs(wrapAngle(joined.theta - true_motion.theta)), 0.45 * M_PI / 180.0);
  for (size_t k = 39; k < unsearched.size(); ++k) EXPECT_EQ(unsearched[k], FrameStatus::lost) << k;
  const Pose2 unjoined = between(lost[38].T_world_robot, lost[45].T_world_robot);
  EXPECT_LT(std::abs(wrapAngle(unjoined.theta - true_motion.theta)), 1.5 * M_PI / 180.0);  // measured 0.34 degrees
  std::vector<FrameStatus> unmeasured;
  const Trajectory guessed = run(0.0, unmeasured, 0);
  const Pose2 previous_turn = between(guessed[38].T_world_robot, guessed[45].T_world_robot);
  EXPECT_GT(std::abs(wrapAngle(previous_turn.theta - true_motion.theta)), 45.0 * M_PI / 180.0);
}

TEST(Relocalization, AQuarterTurnLostOnCarpetUnderTheOutdoorLookIsFoundByItsSpectra) {
  // The quarter turn above, with the search off: the images of frames 39 and 40 are registered with frame 38's by
  // their spectra (the turn from the magnitudes, the shift from the phase correlation), both less the mean of the
  // recent images. The two registrations agree through the lost segment's odometry, so frame 40 joins the map.
  const QuarterTurnOnCarpet quarter_turn;
  const auto run = [&](double min_peak, std::vector<FrameStatus>& status) {
    return quarter_turn.run(
        [&](Config& config) {
          config.odometry_checks.bridge_search_turn_deg = 0.0;
          config.odometry_checks.bridge_spectral_min_peak = min_peak;
        },
        status);
  };
  std::vector<FrameStatus> registered, unregistered;
  const Trajectory found = run(0.15, registered);
  run(0.0, unregistered);
  EXPECT_EQ(registered[39], FrameStatus::lost);
  EXPECT_EQ(registered[40], FrameStatus::relocalized);
  for (size_t k = 41; k < registered.size(); ++k) EXPECT_NE(registered[k], FrameStatus::lost) << k;
  for (size_t k = 39; k < unregistered.size(); ++k) EXPECT_EQ(unregistered[k], FrameStatus::lost) << k;
  // The quarter turn and the frames after it sit where the truth puts them (measured 3.8 mm and 0.07 degrees, 5.5 mm
  // and 0.16 degrees).
  const Pose2 turned = between(found[38].T_world_robot, found[39].T_world_robot);
  const Pose2 true_turn = quarter_turn.trueMotion(38, 39);
  EXPECT_LT((turned.translation() - true_turn.translation()).norm(), 0.008);
  EXPECT_LT(std::abs(wrapAngle(turned.theta - true_turn.theta)), 0.5 * M_PI / 180.0);
  const Pose2 joined = between(found[38].T_world_robot, found[45].T_world_robot);
  const Pose2 true_motion = quarter_turn.trueMotion(38, 45);
  EXPECT_LT((joined.translation() - true_motion.translation()).norm(), 0.008);
  EXPECT_LT(std::abs(wrapAngle(joined.theta - true_motion.theta)), 0.5 * M_PI / 180.0);
}

TEST(Relocalization, OnTilesABlankFrameIsBridgedToTheRightTileNotALookAlike) {
  // Tiles repeat every 4 cm; a motion two frames long (2 cm) is matched one tile over as well as right. The bridge
  // believes it only without a rival transform and at the robot's speed (the prediction, 2 cm, give or take
  // 2 cm + 50%: a tile either way is outside), so frame 121 joins at the right tile. Global localization alone
  // refuses the repeated floor: with the bridge off the robot stays lost.
  auto settings = session("tiles", sim::PathKind::loop, 400, 5);
  settings.ground_seed.reset();
  const sim::SequenceSimulator simulator(settings);
  const auto run = [&](int bridge_max_frames, std::vector<FrameStatus>& status) {
    Config config = configFor(settings);
    config.odometry_checks.bridge_max_frames = bridge_max_frames;
    Slam slam(config, shippedVocabulary());
    for (int i = 0; i < 130; ++i) {
      const cv::Mat image = i == 120 ? cv::Mat(simulator.renderFrame(i).size(), CV_8U, cv::Scalar(128)) : simulator.renderFrame(i);
      status.push_back(slam.process(image, static_cast<double>(i)).status);
    }
    slam.finish();
    return slam.trajectory();
  };
  std::vector<FrameStatus> bridged, unbridged;
  const Trajectory estimated = run(3, bridged);
  run(0, unbridged);
  EXPECT_EQ(bridged[120], FrameStatus::lost);
  EXPECT_EQ(bridged[121], FrameStatus::relocalized);
  const Pose2 joined = between(estimated[119].T_world_robot, estimated[121].T_world_robot);
  const Pose2 true_motion = between(simulator.groundTruth()[119], simulator.groundTruth()[121]);
  EXPECT_LT((joined.translation() - true_motion.translation()).norm(), 0.001);
  for (int i = 121; i < 130; ++i) EXPECT_EQ(unbridged[size_t(i)], FrameStatus::lost) << i;
}

TEST(Relocalization, LostAtTheStartTheMapStartsWhereTrackingDoes) {
  // Frame 1 is blank (a covered lens): frames 1 and 2 cannot be measured, before there is a map to come back to.
  // The map starts again at frame 2; frames 0 and 1 are reported but not measured, and the rest is tracked.
  auto settings = session("asphalt", sim::PathKind::loop, 400, 5);
  settings.ground_seed.reset();
  const sim::SequenceSimulator simulator(settings);
  const auto run = [&](const Config& config, std::vector<FrameResult>& results) {
    Slam slam(config, shippedVocabulary());
    for (int i = 0; i < 40; ++i) {
      const cv::Mat image = i == 1 ? cv::Mat(simulator.renderFrame(i).size(), CV_8U, cv::Scalar(128)) : simulator.renderFrame(i);
      results.push_back(slam.process(image, static_cast<double>(i)));
    }
    slam.finish();
    return slam.trajectory();
  };
  std::vector<FrameResult> restarted;
  const Trajectory t = run(configFor(settings), restarted);
  EXPECT_EQ(restarted[1].statusName(), "lost_too_few_matches");
  EXPECT_EQ(restarted[2].statusName(), "lost_too_few_matches");
  for (int i = 3; i < 40; ++i) EXPECT_EQ(restarted[size_t(i)].statusName(), "ok") << i;
  ASSERT_EQ(t.size(), 40u);
  EXPECT_FALSE(t[0].measured);
  EXPECT_FALSE(t[1].measured);
  for (int i = 2; i < 40; ++i) EXPECT_TRUE(t[size_t(i)].measured) << i;
  // The new map's frames keep their true shape: frame 39 relative to frame 2 within a millimetre.
  const Pose2 estimated = between(t[2].T_world_robot, t[39].T_world_robot);
  const Pose2 truth = between(simulator.groundTruth()[2], simulator.groundTruth()[39]);
  EXPECT_LT((estimated.translation() - truth.translation()).norm(), 0.001);
  // Without the restart, frame 1 starts a lost segment that has to be joined to frame 0's ground: by global
  // localization (on asphalt that works: frames 2 and 3 agree; on a repeated floor it is a look-alike's game), or
  // at once by frame 2's features fitted to frame 0's (the bridge, odometry.bridge_max_frames).
  Config relocalizing = configFor(settings);
  relocalizing.odometry_checks.restart_map_below_frames = 0;
  relocalizing.odometry_checks.bridge_max_frames = 0;
  std::vector<FrameResult> lost;
  run(relocalizing, lost);
  EXPECT_EQ(lost[1].statusName(), "lost_too_few_matches");
  EXPECT_EQ(lost[2].statusName(), "lost_too_few_matches");
  EXPECT_EQ(lost[3].statusName(), "relocalized");
  Config bridging = configFor(settings);
  bridging.odometry_checks.restart_map_below_frames = 0;
  std::vector<FrameResult> bridged;
  run(bridging, bridged);
  EXPECT_EQ(bridged[1].statusName(), "lost_too_few_matches");
  EXPECT_EQ(bridged[2].statusName(), "relocalized");
  for (int i = 3; i < 40; ++i) EXPECT_EQ(bridged[size_t(i)].statusName(), "ok") << i;
}

TEST(Relocalization, ASecondSessionOnAPriorMapComesOutInTheMapFrame) {
  auto first_settings = session("concrete", sim::PathKind::lawnmower, 300, 1);
  first_settings.path.lane_length_m = 0.5;
  const sim::SequenceSimulator first(first_settings);
  const Config config = configFor(first_settings);
  Slam mapping(config, shippedVocabulary());
  for (int i = 0; i < first.frameCount(); ++i) mapping.process(first.renderFrame(i), i);
  mapping.finish();
  const FeatureMap map = parseMap(formatMap(*mapping.featureMap(), mapping.mapSegment()), "memory", shippedVocabulary());

  auto second_settings = session("concrete", sim::PathKind::random_walk, 120, 2);
  second_settings.path.area_m = 0.3;
  second_settings.wet_after = 0.0;  // the floor looks different the second time
  const sim::SequenceSimulator second(second_settings);
  Slam session2(config, shippedVocabulary());
  session2.usePriorMap(map);
  for (int i = 0; i < second.frameCount(); ++i) session2.process(second.renderFrame(i), i);
  session2.finish();
  // The map frame is the first session's first pose.
  const Pose2 T_world_map = first.groundTruth().front();
  int within = 0;
  const Trajectory estimate = session2.trajectory();
  ASSERT_EQ(estimate.size(), 120u);
  for (size_t i = 0; i < estimate.size(); ++i) {
    const Pose2 error = second.groundTruth()[i].inverse() * (T_world_map * estimate[i].T_world_robot);
    within += error.translation().norm() < 0.01 && std::abs(error.theta) < M_PI / 180.0 ? 1 : 0;
  }
  EXPECT_GE(within, 114) << "of 120 within 1 cm and 1 degree";
}

TEST(FeatureMap, FeaturesAreStoredOnceIndexedByWordAndFollowTheirKeyframe) {
  const auto settings = session("asphalt", sim::PathKind::loop, 10, 1);
  const sim::SequenceSimulator simulator(settings);
  const FramePreparer preparer(configFor(settings));
  const GroundFeatures features = preparer.prepare(simulator.renderFrame(0), 0).features;
  ASSERT_TRUE(features.hasOrientations());
  FeatureMap map(shippedVocabulary());
  const Pose2 T_map_a(0.3, -0.2, 0.7);
  map.addAnchor(0, T_map_a, 0, features);
  const size_t stored = map.features().size();
  EXPECT_GT(stored, 0.9 * static_cast<double>(features.size()));  // a frame's own features are distinct
  // The same features seen again from the same place add nothing: they are on the map already.
  map.addAnchor(1, T_map_a, 0, features);
  EXPECT_EQ(map.features().size(), stored);
  // Every feature is in the posting list of its word.
  size_t postings = 0;
  for (int w = 0; w < map.vocabulary().wordCount(); ++w) postings += map.postings(w).size();
  EXPECT_EQ(postings, stored);
  const MapFeature& f = map.features().front();
  EXPECT_LT((map.positionOf(f) - T_map_a * f.point.cast<double>()).norm(), 1e-12);
  // An optimisation that moves the keyframe moves its features.
  map.moveAnchor(0, Pose2(1.0, 2.0, -0.3));
  EXPECT_LT((map.positionOf(f) - Pose2(1.0, 2.0, -0.3) * f.point.cast<double>()).norm(), 1e-12);
  EXPECT_NEAR(map.angleOf(f), wrapAngle(-0.3 + f.angle_rad), 1e-6);
  EXPECT_EQ(sizeof(MapFeature), 52u);  // 49 bytes of data, aligned
}

TEST(GlobalLocalization, AFrameLocalizesOnAMapOfItselfAtAnyPoseAndHeading) {
  const auto settings = session("carpet", sim::PathKind::loop, 10, 1);
  const sim::SequenceSimulator simulator(settings);
  const FramePreparer preparer(configFor(settings));
  const GroundFeatures features = preparer.prepare(simulator.renderFrame(0), 0).features;
  for (const Pose2& T_map_robot : {Pose2(0.0, 0.0, 0.0), Pose2(12.5, -3.25, 2.9), Pose2(-0.4, 7.0, -1.6)}) {
    FeatureMap map(shippedVocabulary());
    map.addAnchor(0, T_map_robot, 0, features);
    const Localization l = localizeGlobally(map, features, LocalizationSettings{}, Config{}.odometry);
    ASSERT_TRUE(l.ok()) << localizationStatusName(l.status);
    EXPECT_LT((l.T_map_robot.translation() - T_map_robot.translation()).norm(), 1e-4);
    EXPECT_LT(std::abs(wrapAngle(l.T_map_robot.theta - T_map_robot.theta)), 1e-3);
    EXPECT_EQ(l.anchor, 0);
    EXPECT_LT(l.T_anchor_robot.translation().norm(), 1e-4);
  }
  // Features that are not on the map find nothing, and say so.
  FeatureMap elsewhere(shippedVocabulary());
  elsewhere.addAnchor(0, Pose2(), 0, preparer.prepare(simulator.renderFrame(0), 0).features);
  auto other_settings = session("concrete", sim::PathKind::loop, 10, 9);
  other_settings.ground_seed = 99;
  const sim::SequenceSimulator other(other_settings);
  const Localization none = localizeGlobally(elsewhere, preparer.prepare(other.renderFrame(0), 0).features, LocalizationSettings{},
                                             Config{}.odometry);
  EXPECT_FALSE(none.ok());
}

TEST(GlobalLocalization, APoseOnlyTheFeaturesNearnessConfirmsIsRefused) {
  // Guided re-matching pairs each feature with the map features within a few millimetres of where the peak puts it,
  // a lone one whatever its descriptor: on a dense map, nearness alone "confirms" any pose. A frame's features on a
  // map of themselves, all but `kept` of them with descriptors of another floor's features: the kept ones vote the
  // peak, the others are paired by nearness alone. The pose needs localization.min_strong_inliers (15) inliers
  // whose descriptors agree within strong_hamming (40) bits.
  const auto settings = session("carpet", sim::PathKind::loop, 10, 1);
  const sim::SequenceSimulator simulator(settings);
  const FramePreparer preparer(configFor(settings));
  const GroundFeatures features = preparer.prepare(simulator.renderFrame(0), 0).features;
  auto other_settings = session("asphalt", sim::PathKind::loop, 10, 9);
  other_settings.ground_seed = 99;
  const GroundFeatures others = preparer.prepare(sim::SequenceSimulator(other_settings).renderFrame(0), 0).features;
  ASSERT_GE(others.size(), features.size());
  const Pose2 T_map_robot(0.4, -0.1, 1.2);
  FeatureMap map(shippedVocabulary());
  map.addAnchor(0, T_map_robot, 0, features);
  const auto localizedKeeping = [&](int kept, bool strong_asked) {
    GroundFeatures query = features;
    query.descriptors = features.descriptors.clone();
    for (int i = kept; i < query.descriptors.rows; ++i) others.descriptors.row(i).copyTo(query.descriptors.row(i));
    LocalizationSettings s;
    if (!strong_asked) s.min_strong_inliers = 0;
    return localizeGlobally(map, query, s, Config{}.odometry);
  };
  // 12 agreeing features vote a peak; nearness pairs enough of the rest to pass min_inliers.
  const Localization by_nearness = localizedKeeping(12, false);
  EXPECT_TRUE(by_nearness.ok()) << localizationStatusName(by_nearness.status);
  EXPECT_GE(by_nearness.inliers, 30);  // localization.min_inliers
  EXPECT_LT(by_nearness.strong_inliers, 15);
  const Localization refused = localizedKeeping(12, true);
  EXPECT_EQ(refused.status, LocalizationStatus::too_few_inliers);
  // 40 agreeing features: localized, exactly.
  const Localization agreeing = localizedKeeping(40, true);
  ASSERT_TRUE(agreeing.ok()) << localizationStatusName(agreeing.status);
  EXPECT_GE(agreeing.strong_inliers, 30);
  EXPECT_LT((agreeing.T_map_robot.translation() - T_map_robot.translation()).norm(), 1e-4);
  EXPECT_LT(std::abs(wrapAngle(agreeing.T_map_robot.theta - T_map_robot.theta)), 1e-3);
}

TEST(Relocalization, TheRobotsOwnArtifactsStayOutOfTheMap) {
  // The heavy outdoor look: a dark shadow, dirt on the lens, a saturating glare and a quarter of the image
  // hidden by a bumper with bolts. Those stay at the same pixels in every image; if the map kept them, any
  // later image would "localize" where the map's first keyframes were. SLAM maps the first 60 frames of a
  // loop; frames 100-160, on ground never mapped, must not localize anywhere.
  sim::SimulationSettings s = session("concrete", sim::PathKind::loop, 200, 47);
  s.path.laps = 1;  // frames 100-160: the far side of the circle
  s.artifacts = {0.8, 10, 1.2, 0.25};
  const sim::SequenceSimulator simulator(s);
  Slam slam(configFor(s), shippedVocabulary());
  for (int i = 0; i < 60; ++i) slam.process(simulator.renderFrame(i), i);
  slam.finish();
  ASSERT_GT(slam.featureMap()->anchors().size(), 3u);
  const FramePreparer preparer(configFor(s));
  // As the localize command does (votes compared, LocalizationSettings::max_vote_ratio): nothing localizes.
  // With the votes not compared (unrepeated_max_vote_ratio, in a run on a floor that does not repeat), frame 125
  // localizes on frame 0's own pose (80 inliers: frame 0 became a keyframe before the artifact mask had learnt),
  // which a run refuses (localization.min_anchor_offset_*): every such localization must lie there.
  LocalizationSettings compared;
  compared.unrepeated_max_vote_ratio = compared.max_vote_ratio;
  const LocalizationSettings uncompared;
  int localized = 0, off_an_anchors_pose = 0;
  for (int i = 100; i < 160; i += 5) {
    for (int j = 0; j < 60; ++j) {
      ASSERT_GT((simulator.groundTruth()[size_t(i)].translation() - simulator.groundTruth()[size_t(j)].translation()).norm(), 0.2);
    }
    const GroundFeatures features = preparer.prepare(simulator.renderFrame(i), i).features;
    localized += localizeGlobally(*slam.featureMap(), features, compared, configFor(s).odometry).ok() ? 1 : 0;
    const Localization l = localizeGlobally(*slam.featureMap(), features, uncompared, configFor(s).odometry);
    const bool on_anchor = l.T_anchor_robot.translation().norm() < uncompared.min_anchor_offset_m &&
                           std::abs(l.T_anchor_robot.theta) < uncompared.min_anchor_offset_rad;
    off_an_anchors_pose += l.ok() && !on_anchor ? 1 : 0;
  }
  EXPECT_EQ(localized, 0);
  EXPECT_EQ(off_an_anchors_pose, 0);
}

TEST(Relocalization, OnAFloorThatDoesNotRepeatAWeakWinnersVotesAreNotComparedWithChancePeaks) {
  // Carpet under the outdoor look (shadow, dirt, glare, bumper, rocking, blur), carried 80 frames along its loop
  // (250-329 never seen). The landing frames collect a dozen votes; a chance peak often has 70% of them, though
  // only the winner verifies. Odometry never met a rival repetition, so the votes are not compared
  // (localization.unrepeated_max_vote_ratio 1): the robot relocalizes at frame 332; comparing them (0.7, the rule
  // on a repeated floor) it stays lost until 334.
  const sim::SimulationSettings s = carpetLoopUnderTheOutdoorLook(41);
  const sim::SequenceSimulator simulator(s);
  const auto run = [&](double unrepeated_max_vote_ratio, int& relocalized_at) {
    Config config = configFor(s);
    config.localization.unrepeated_max_vote_ratio = unrepeated_max_vote_ratio;
    config.odometry_checks.bridge_max_frames = 0;
    Slam slam(config, shippedVocabulary());
    Trajectory truth;
    for (int i = 0; i < 345; ++i) {
      if (i >= 250 && i < 330) continue;
      const FrameResult r = slam.process(simulator.renderFrame(i), static_cast<double>(i));
      truth.push_back({static_cast<double>(i), simulator.groundTruth()[static_cast<size_t>(i)]});
      if (r.status == FrameStatus::relocalized && relocalized_at < 0) relocalized_at = i;
    }
    slam.finish();
    return evaluateTrajectory(truth, slam.trajectory()).metrics;
  };
  int relaxed_at = -1, strict_at = -1;
  const TrajectoryMetrics relaxed = run(1.0, relaxed_at);
  run(0.7, strict_at);
  EXPECT_EQ(relaxed_at, 332);
  EXPECT_EQ(strict_at, 334);
  // Where it landed is right: the whole run within 5 mm (measured 3.4 mm) and 0.5 degrees (0.29).
  EXPECT_EQ(relaxed.measured_frames, relaxed.groundtruth_frames);
  EXPECT_LT(relaxed.ate_rmse_m, 0.005);
  EXPECT_LT(relaxed.rotation_mae_deg, 0.5);
}

TEST(Relocalization, OnCarpetASegmentLostAtAGapJoinsTheMapWhereItRunsBesideAMappedLane) {
  // Carpet under the outdoor look, a lawnmower of 30 cm lanes 8 cm apart; frames 50-56 dropped without a trace in
  // the timestamps, in the second lane. Frame 57's motion, 8 steps at the speed of one, is refused and the previous
  // step assumed (no steps model here), 7 cm short. Global localization is off (no peak has enough votes), and so is
  // the bridge to the last tracked frame: the segment lost there runs beside the first lane, whose places lie within
  // the reach of the unknown motion at the loss (loop_closure.lost_reach_m). Verified against them as loop closures
  // are, two frames that agree with odometry join it to the map; with the reach 0 it stays lost to the end.
  auto s = carpetLoopUnderTheOutdoorLook(5);
  s.path.kind = sim::PathKind::lawnmower;
  s.path.lane_length_m = 0.3;
  s.path.frames = 130;
  const sim::SequenceSimulator simulator(s);
  std::vector<int> images;  // the simulator's frame of each processed one
  for (int i = 0; i < simulator.frameCount(); ++i) {
    if (i < 50 || i >= 57) images.push_back(i);
  }
  const auto run = [&](double lost_reach_m, std::vector<FrameStatus>& status) {
    Config config = configFor(s);
    config.localization.min_votes = 1000000;
    config.odometry_checks.bridge_max_frames = 0;
    config.odometry_checks.decisive_inlier_share = 2.0;
    config.odometry_checks.repetition_max_steps = 0;
    config.loop_closure.lost_reach_m = lost_reach_m;
    Slam slam(config, shippedVocabulary());
    for (size_t k = 0; k < images.size(); ++k) {
      // Stamped one step apart: the drop leaves no trace in the timestamps.
      status.push_back(slam.process(simulator.renderFrame(images[k]), static_cast<double>(k)).status);
    }
    slam.finish();
    return std::make_pair(slam.trajectory(), slam.loopCandidates());
  };
  std::vector<FrameStatus> rejoined, unjoined;
  const auto [found, candidates] = run(0.08, rejoined);
  const auto [guessed, unused] = run(0.0, unjoined);
  const size_t loss = 50;  // frame 57
  ASSERT_EQ(images[loss], 57);
  EXPECT_EQ(rejoined[loss], FrameStatus::lost);
  EXPECT_EQ(rejoined[loss + 1], FrameStatus::relocalized);
  for (size_t k = loss + 2; k < rejoined.size(); ++k) EXPECT_NE(rejoined[k], FrameStatus::lost) << images[k];
  for (size_t k = loss; k < unjoined.size(); ++k) EXPECT_EQ(unjoined[k], FrameStatus::lost) << images[k];
  // The gap, frame 49 to frame 57: placed by the join (measured 3.1 mm off), guessed one step on without it (73 mm).
  const auto truth = [&](size_t k) { return simulator.groundTruth()[static_cast<size_t>(images[k])]; };
  const Pose2 true_gap = between(truth(loss - 1), truth(loss));
  const auto error_m = [&](const Trajectory& t) {
    return (between(t[loss - 1].T_world_robot, t[loss].T_world_robot).translation() - true_gap.translation()).norm();
  };
  EXPECT_LT(error_m(found), 0.005);
  EXPECT_GT(error_m(guessed), 0.05);
  // Every accepted loop closure and join is right (within 2 cm and 2 degrees).
  int joins = 0;
  for (const LoopCandidate& c : candidates) {
    if (!c.accepted()) continue;
    const Pose2 t = between(truth(static_cast<size_t>(c.frame_a)), truth(static_cast<size_t>(c.frame_b)));
    EXPECT_LT((c.T_a_b.translation() - t.translation()).norm(), 0.02) << c.frame_a << " " << c.frame_b;
    EXPECT_LT(std::abs(wrapAngle(c.T_a_b.theta - t.theta)), 2.0 * M_PI / 180.0) << c.frame_a << " " << c.frame_b;
    joins += c.frame_b == static_cast<int>(loss) || c.frame_b == static_cast<int>(loss + 1) ? 1 : 0;
  }
  EXPECT_EQ(joins, 2);
}
