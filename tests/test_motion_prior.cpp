// The robot's own motion tells a repeated floor's repetitions apart: known candidates, known choices.
#include <cmath>
#include <optional>

#include <gtest/gtest.h>

#include "groundslam/core/MotionPrior.hpp"
#include "groundslam/core/RigidFit.hpp"

using namespace groundslam;

namespace {

constexpr double kDeg = M_PI / 180.0;

/// k steps of `step`, composed.
Pose2 steps(const Pose2& step, int k) {
  Pose2 T;
  for (int j = 0; j < k; ++j) T = T * step;
  return T;
}

}  // namespace

TEST(MotionPrior, KStepsTurnEvenlyAndOneStepTurnsAsUsualOrOnTheSpot) {
  const Pose2 step(0.0, -0.01, 1.75 * kDeg);
  const MotionPrior prior(step, 1, 8, MotionPriorSettings{});
  // Turned by six steps' worth (10.5 degrees): six steps, each turning as the usual one. A single step would
  // have to turn 8.75 degrees more than usual: more likely a gap.
  const std::vector<PredictedMotion> turned = prior.predictions(6 * step.theta);
  ASSERT_EQ(turned.size(), 1u);
  EXPECT_EQ(turned[0].steps, 6);
  EXPECT_LT((turned[0].T_prev_curr.translation() - steps(step, 6).translation()).norm(), 1e-12);
  // Doubt: 4 mm, 20% of a step per step, and the tilt's lever arm (none set here).
  EXPECT_NEAR(turned[0].sigma_m, 0.004 + 0.2 * 6 * 0.01, 1e-12);
  // A usual turn: one step (two steps would turn twice as much).
  const std::vector<PredictedMotion> usual = prior.predictions(step.theta - 2.0 * kDeg);
  ASSERT_EQ(usual.size(), 1u);
  EXPECT_EQ(usual[0].steps, 1);
  // A quarter turn on the spot keeps one step's translation.
  const std::vector<PredictedMotion> spun = prior.predictions(90.0 * kDeg);
  ASSERT_EQ(spun.size(), 1u);
  EXPECT_EQ(spun[0].steps, 1);
  EXPECT_LT((spun[0].T_prev_curr.translation() - step.translation()).norm(), 1e-12);
  // A sudden 30-degree turn is neither: nothing predicts it.
  EXPECT_TRUE(prior.predictions(30.0 * kDeg).empty());
  // Timestamps that show six missing steps allow those only.
  EXPECT_TRUE(MotionPrior(step, 6, 6, MotionPriorSettings{}).predictions(step.theta).empty());
  EXPECT_EQ(MotionPrior(step, 6, 6, MotionPriorSettings{}).predictions(6 * step.theta).size(), 1u);
}

TEST(MotionPrior, AGapWhileTurningIsToldFromItsRepetitions) {
  // Frames dropped while the robot turned 2 degrees per 1 cm step: four steps later it is 4 cm on, turned by
  // 8 degrees. The floor repeats every 4 cm, so RANSAC also offers the truth shifted by a tile ahead, behind
  // and to either side, each with the same turn. Only four steps turn by 8 degrees (three or five turn 2
  // degrees less or more), and only one candidate lies where four steps go.
  const Pose2 step(0.0, -0.01, 2.0 * kDeg);
  const Pose2 truth = steps(step, 4) * Pose2(0.002, 0.003, 0.0);  // the fit a few millimetres off
  std::vector<Pose2> candidates;
  for (const Eigen::Vector2d& shift : std::vector<Eigen::Vector2d>{Eigen::Vector2d(0.04, 0.0), Eigen::Vector2d(-0.04, 0.0),
                                                                   Eigen::Vector2d(0.0, -0.04), Eigen::Vector2d(0.0, 0.0)}) {
    candidates.emplace_back(truth.x + shift.x(), truth.y + shift.y(), truth.theta);
  }
  const MotionPrior prior(step, 1, 8, MotionPriorSettings{});
  ASSERT_TRUE(prior.choose(candidates).has_value());
  EXPECT_EQ(*prior.choose(candidates), 3u);
  EXPECT_LT(prior.doubtsOff(candidates[3]), 0.5);
  for (size_t i = 0; i < 3; ++i) EXPECT_GT(prior.doubtsOff(candidates[i]), 2.5) << i;
  // The repetition a tile behind, where the robot started, would be a single step with a sudden 6-degree turn
  // (not predicted) or four steps 4 cm short of where they go.
  EXPECT_GT(prior.doubtsOff(Pose2(truth.x, truth.y + 0.04, truth.theta)), 2.5);
  // Six steps on, the doubt is 1.6 cm (20% of six steps and 4 mm): a 3.5 cm tile to the side is too close to
  // tell, and nothing is chosen.
  const Pose2 far = steps(step, 6);
  EXPECT_FALSE(prior.choose({far, Pose2(far.x + 0.035, far.y, far.theta)}).has_value());
}

TEST(MotionPrior, AGapOnAStraightLaneStaysAmbiguous) {
  // Driving straight, 6 cm on and the repetition 4 cm behind it (2 cm on) are both a whole number of steps:
  // nothing tells them apart, and nothing is chosen. Told by the timestamps that six steps passed, the 6 cm is.
  const Pose2 step(0.0, -0.01, 0.0);
  const std::vector<Pose2> candidates{Pose2(0.0, -0.06, 0.0), Pose2(0.0, -0.02, 0.0)};
  EXPECT_FALSE(MotionPrior(step, 1, 8, MotionPriorSettings{}).choose(candidates).has_value());
  const auto timed = MotionPrior(step, 6, 6, MotionPriorSettings{}).choose(candidates);
  ASSERT_TRUE(timed.has_value());
  EXPECT_EQ(*timed, 0u);
}

TEST(MotionPrior, ATurnOnTheSpotKeepsTheStepAndNothingFarIsChosen) {
  // A quarter turn between two frames: the robot still made its 1 cm step. The repetition one tile over is
  // refused even with the tilt's lever arm in the doubt (25 cm x 1 degree: 6 mm at a quarter turn).
  const Pose2 step(0.01, 0.0, 0.0);
  MotionPriorSettings settings;
  settings.lever_m = 0.25 * kDeg;
  const MotionPrior prior(step, 1, 8, settings);
  const std::vector<Pose2> candidates{Pose2(0.05, 0.0, 90 * kDeg), Pose2(0.012, 0.003, 90 * kDeg)};
  ASSERT_TRUE(prior.choose(candidates).has_value());
  EXPECT_EQ(*prior.choose(candidates), 1u);
  // Only repetitions, none where the robot went: none chosen.
  EXPECT_FALSE(prior.choose({Pose2(0.05, 0.0, 90 * kDeg), Pose2(-0.03, 0.0, 90 * kDeg)}).has_value());
}

TEST(MotionPrior, OnAStraightLaneTheMatchesDecideWhenOneMotionHasMostOfThem) {
  // One 1 cm step, and the repetition a tile on (five steps: a gap without a trace would put it there). Both are
  // where the robot can be; the matches decide when one has twice the other's inliers (measured on the outdoor
  // tiles: 63 against 13, the repetition overlapping the image less). A rival to the side is no step at all.
  const Pose2 step(0.01, 0.0, 0.0);
  const MotionPrior prior(step, 1, 8, MotionPriorSettings{});
  const std::vector<Pose2> candidates{Pose2(0.0098, -0.003, 0.0), Pose2(0.0482, -0.0034, 0.0), Pose2(0.0086, 0.036, 0.0)};
  EXPECT_FALSE(prior.choose(candidates).has_value());  // by the steps alone: two motions
  const auto chosen = prior.choose(candidates, {63, 13, 28});
  ASSERT_TRUE(chosen.has_value());
  EXPECT_EQ(*chosen, 0u);
  // The rival to the side is ruled out by the steps: its 40 inliers do not count against the step.
  EXPECT_EQ(prior.choose(candidates, {63, 13, 40}), std::optional<size_t>(0));
  // Not twice: nothing chosen.
  EXPECT_FALSE(prior.choose(candidates, {63, 40, 28}).has_value());
  MotionPriorSettings off;
  off.support_ratio = 0.0;
  EXPECT_FALSE(MotionPrior(step, 1, 8, off).choose(candidates, {63, 13, 28}).has_value());
}

TEST(MotionPrior, TheLikeliestMotionIsTheBestSupportedOneTheStepsAllow) {
  // A frame dropped on a straight lane over 4 cm tiles: two steps on (2 cm, the truth, 37 inliers) and the
  // repetition a tile on (6 cm, six steps, 25 inliers) are both where the robot can be, and nothing is believed
  // (not twice the inliers). The likeliest is the two steps; the repetition a tile to the side, with the most
  // inliers of all (48), is no motion of the robot's and never the likeliest (measured on the outdoor tiles).
  const Pose2 step(0.0105, 0.0002, 0.0);
  const MotionPrior prior(step, 1, 8, MotionPriorSettings{});
  const std::vector<Pose2> candidates{Pose2(-0.0212, 0.0362, 0.0), Pose2(0.0187, -0.0037, 0.0), Pose2(0.0586, -0.0038, 0.0)};
  const std::vector<int> support{48, 37, 25};
  EXPECT_FALSE(prior.choose(candidates, support).has_value());
  EXPECT_EQ(prior.likeliest(candidates, support), std::optional<size_t>(1));
  EXPECT_EQ(prior.likeliest(candidates, {48, 25, 37}), std::optional<size_t>(2));
  // Only the repetition to the side: no likeliest motion.
  EXPECT_FALSE(prior.likeliest({candidates[0]}, {48}).has_value());
  // Frames dropped at the end of a turn (1.8 degrees a step): five steps on, turned 9.1 degrees, 13 inliers; one
  // step turning 7.3 degrees more than usual has 31, overlapping the image more. The five steps explain the turn:
  // they are the likeliest, and the single step is never believed; where it is too near the five steps for them to
  // be believed by the steps alone (margin 3 here), nothing is (development seed 41, tiles loop, frame 141).
  const Pose2 turning(0.0, -0.0099, 1.8 * kDeg);
  MotionPriorSettings wide;
  wide.margin = 3.0;
  const std::vector<Pose2> arc{Pose2(-0.0041, -0.0135, 9.21 * kDeg), Pose2(0.0345, -0.0050, 9.05 * kDeg),
                               Pose2(0.0040, -0.0520, 9.23 * kDeg)};
  for (const MotionPrior& turning_prior : {MotionPrior(turning, 1, 8, MotionPriorSettings{}), MotionPrior(turning, 1, 8, wide)}) {
    ASSERT_LE(turning_prior.doubtsOff(arc[2]), 1.0);
    ASSERT_LE(turning_prior.looseDoubtsOff(arc[0]), 1.0);  // one step with a sudden turn
    ASSERT_GT(turning_prior.doubtsOff(arc[0]), 1.0);
    EXPECT_EQ(turning_prior.likeliest(arc, {31, 24, 13}), std::optional<size_t>(2));
  }
  EXPECT_EQ(MotionPrior(turning, 1, 8, MotionPriorSettings{}).choose(arc, {31, 24, 13}), std::optional<size_t>(2));
  EXPECT_FALSE(MotionPrior(turning, 1, 8, wide).choose(arc, {31, 24, 13}).has_value());
  // Supports that do not belong to the candidates: none.
  EXPECT_FALSE(prior.likeliest(candidates, {48, 37}).has_value());
}

TEST(MotionPrior, AfterATurnOnTheSpotTheStepsGoOnAsBeforeOrTurnedWithTheCamera) {
  // Before a quarter turn the robot stepped 1 cm along x in the camera's frame, turning 1.8 degrees a step. Its
  // path goes on where it went (the camera turned, the path did not): now the step is 1 cm along -y. A tile on
  // along x is four of the old steps, with the support of a repetition.
  const Pose2 before(0.01, 0.0, 1.8 * kDeg);
  const Pose2 turned(0.0, -0.01, 1.8 * kDeg);
  const std::vector<Pose2> candidates{Pose2(0.0002, -0.0099, 1.8 * kDeg), Pose2(0.0402, -0.0099, 1.8 * kDeg)};
  const MotionPrior both({before, turned}, 1, 8, MotionPriorSettings{});
  ASSERT_EQ(both.predictions(1.8 * kDeg).size(), 2u);  // one step of each; more steps would turn more
  EXPECT_LT(both.doubtsOff(candidates[0]), 0.1);
  EXPECT_EQ(both.choose(candidates, {60, 20}), std::optional<size_t>(0));
  // Told only the step before the turn, the true motion is 2.3 doubts off and the repetition is closer: none.
  EXPECT_FALSE(MotionPrior(before, 1, 8, MotionPriorSettings{}).choose(candidates, {60, 20}).has_value());
}

TEST(MotionPrior, ASuddenChangeOfTurnIsOneStepOnlyWhenTheMatchesSaySo) {
  // The robot turned 14 degrees a step, now goes straight: no prediction has that turn. One step's translation
  // with 53 inliers against repetitions 4 cm away: chosen by the matches; without them, when a repetition
  // within reach has more than half the inliers, or when any candidate has more, not.
  const Pose2 step(-0.001, -0.0105, 14.3 * kDeg);
  const MotionPrior prior(step, 1, 8, MotionPriorSettings{});
  const std::vector<Pose2> candidates{Pose2(0.0016, -0.0098, 0.15 * kDeg), Pose2(0.0322, 0.0153, 0.38 * kDeg),
                                      Pose2(0.0573, -0.0157, 0.05 * kDeg)};
  EXPECT_TRUE(std::isinf(prior.doubtsOff(candidates[0])));
  EXPECT_LT(prior.looseDoubtsOff(candidates[0]), 0.6);
  EXPECT_FALSE(prior.choose(candidates).has_value());
  EXPECT_EQ(prior.choose(candidates, {53, 38, 21}), std::optional<size_t>(0));
  // A repetition the steps rule out that has more inliers still vetoes a sudden turn (measured: a 7-frame gap
  // while turning, read as one step turning 15 degrees more than usual, 33 inliers against 37).
  EXPECT_FALSE(prior.choose(candidates, {33, 37, 21}).has_value());
  const std::vector<Pose2> near{candidates[0], Pose2(0.0016, -0.0198, 0.15 * kDeg)};  // a step further, 1 cm on
  EXPECT_FALSE(prior.choose(near, {53, 38}).has_value());
  // Timestamps that show a gap leave no room for a single step.
  EXPECT_FALSE(MotionPrior(step, 3, 3, MotionPriorSettings{}).choose(candidates, {53, 38, 21}).has_value());
}

TEST(RigidFit, RivalsAreTheOtherRepetitionsStrongestFirst) {
  // Points on three 4 cm tiles, each matched to its copy on every tile: the truth and its repetitions one and
  // two tiles over (either way) explain a third of the matches each.
  const Pose2 truth(0.003, 0.001, 0.0);
  std::vector<Eigen::Vector2d> target, source;
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector2d in_tile(0.001 * (i % 7) * 5.0 / 7.0 * 4.0, 0.001 * (i * 13 % 37));
    for (int tile = 0; tile < 3; ++tile) {
      for (int other = 0; other < 3; ++other) {
        source.push_back(in_tile + Eigen::Vector2d(0.04 * tile, 0.0));
        target.push_back(truth * (in_tile + Eigen::Vector2d(0.04 * other, 0.0)));
      }
    }
  }
  FitSettings settings;
  settings.measure_ambiguity = true;
  settings.rival_max_rotation_rad = 1.0 * kDeg;
  settings.ransac_iterations = 2000;
  const RigidEstimate fit = fitRigidTransform(target, source, settings);
  ASSERT_TRUE(fit.ok());
  ASSERT_GE(fit.rivals.size(), 2u);
  EXPECT_LE(fit.rivals.size(), RigidEstimate::kMaxRivals);
  for (size_t i = 0; i < fit.rivals.size(); ++i) {
    // Each rival is the fit shifted by a whole number of tiles along x.
    const Eigen::Vector2d shift = fit.rivals[i].translation() - fit.T_target_source.translation();
    const double tiles = shift.x() / 0.04;
    EXPECT_NEAR(tiles, std::round(tiles), 0.05) << i;
    EXPECT_GE(std::abs(std::round(tiles)), 1.0) << i;
    EXPECT_NEAR(shift.y(), 0.0, 0.001) << i;
    for (size_t j = 0; j < i; ++j) EXPECT_GT((fit.rivals[i].translation() - fit.rivals[j].translation()).norm(), 0.01);
  }
}
