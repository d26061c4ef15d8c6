// The robust SE(2) fit recovers known motions through outliers, and fails as data, never by crashing.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "groundslam/core/RigidFit.hpp"
#include "groundslam/io/ConfigNames.hpp"

using namespace groundslam;

namespace {

struct Correspondences {
  std::vector<Eigen::Vector2d> target, source;
};

/// n ground points in a 15 cm x 10 cm footprint, mapped by T_target_source with 0.1 mm noise;
/// a fraction of them replaced by wrong matches anywhere in the footprint.
Correspondences makeCorrespondences(const Pose2& T_target_source, int n, double outlier_fraction, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-0.075, 0.075), uy(-0.05, 0.05);
  std::normal_distribution<double> noise(0.0, 0.0001);
  Correspondences c;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d source(ux(rng), uy(rng));
    Eigen::Vector2d target = T_target_source * source + Eigen::Vector2d(noise(rng), noise(rng));
    if (i < static_cast<int>(outlier_fraction * n)) target = Eigen::Vector2d(ux(rng), uy(rng)) + T_target_source.translation();
    c.source.push_back(source);
    c.target.push_back(target);
  }
  return c;
}

class KnownMotion : public ::testing::TestWithParam<double> {};

}  // namespace

TEST_P(KnownMotion, RecoveredThroughFortyPercentWrongMatches) {
  for (const RobustLoss loss : {RobustLoss::huber, RobustLoss::cauchy, RobustLoss::geman_mcclure}) {
    const double theta = GetParam() * M_PI / 180.0;
    const Pose2 truth(0.012, -0.007, theta);
    const Correspondences c = makeCorrespondences(truth, 400, 0.4, 3);
    FitSettings settings;
    settings.loss = loss;
    const RigidEstimate fit = fitRigidTransform(c.target, c.source, settings);
    ASSERT_TRUE(fit.ok()) << nameOf(loss) << " " << fitStatusName(fit.status);
    EXPECT_LT((fit.T_target_source.translation() - truth.translation()).norm(), 0.0002) << nameOf(loss);
    EXPECT_LT(std::abs(wrapAngle(fit.T_target_source.theta - truth.theta)) * 180.0 / M_PI, 0.05) << nameOf(loss);
    EXPECT_NEAR(fit.inliers, 240, 12) << nameOf(loss);  // the 60% true matches
    EXPECT_LT(fit.rms_residual_m, 0.0003);
  }
}

INSTANTIATE_TEST_SUITE_P(Rotations, KnownMotion, ::testing::Values(0.0, 7.5, -45.0, 90.0, -90.0, 180.0, 179.9));

TEST(RigidFit, CovarianceGrowsWithTheResidualNoise) {
  const Pose2 truth(0.01, 0.0, 0.2);
  FitSettings settings;
  settings.ransac_inlier_m = 0.004;
  Correspondences sharp = makeCorrespondences(truth, 200, 0.0, 5);
  Correspondences blurry = sharp;
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.001);
  for (auto& p : blurry.target) p += Eigen::Vector2d(noise(rng), noise(rng));
  const RigidEstimate a = fitRigidTransform(sharp.target, sharp.source, settings);
  const RigidEstimate b = fitRigidTransform(blurry.target, blurry.source, settings);
  ASSERT_TRUE(a.ok() && b.ok());
  // Ten times the noise: about a hundred times the variance, two orders of magnitude of covariance score.
  EXPECT_GT(b.covarianceScore() - a.covarianceScore(), 1.5);
  // The translation variance matches sigma^2 / n for 0.1 mm noise and 200 points, within a factor of 2.
  EXPECT_NEAR(std::log10(a.covariance(0, 0)), std::log10(1e-8 / 200.0), 0.3);
}

TEST(RigidFit, DegenerateInputsFailAsData) {
  const FitSettings settings;
  for (int n : {0, 1, 2}) {
    const Correspondences c = makeCorrespondences(Pose2(0.01, 0.0, 0.1), n, 0.0, 1);
    const RigidEstimate fit = fitRigidTransform(c.target, c.source, settings);
    EXPECT_EQ(fit.status, FitStatus::too_few_matches) << n;
  }
  // Every point on one line (e.g. features along a tile joint): the fit is refused.
  Correspondences line;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector2d p(-0.07 + 0.003 * i, 0.01);
    line.source.push_back(p);
    line.target.push_back(Pose2(0.01, 0.0, 0.1) * p);
  }
  EXPECT_EQ(fitRigidTransform(line.target, line.source, settings).status, FitStatus::degenerate);
  // Pure noise: no consensus.
  const Correspondences noise = makeCorrespondences(Pose2(), 60, 1.0, 2);
  EXPECT_EQ(fitRigidTransform(noise.target, noise.source, settings).status, FitStatus::too_few_inliers);
  // Mismatched lengths are refused, not read out of bounds.
  EXPECT_FALSE(fitRigidTransform(line.target, noise.source, settings).ok());
}

namespace {

/// A floor of identical 4 cm tiles moved by `truth`: each of 60 points in a row of three tiles matches one of
/// its copies (the matcher cannot tell them apart), so the true motion and the tile-shifted ones are supported
/// about equally.
Correspondences tiledCorrespondences(const Pose2& truth) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(0.0, 0.04);
  std::normal_distribution<double> noise(0.0, 0.0001);
  Correspondences c;
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector2d in_tile(u(rng), u(rng));
    for (int tile = 0; tile < 3; ++tile) {
      const int matched_tile = (tile + i) % 3;
      c.source.push_back(in_tile + Eigen::Vector2d(0.04 * tile, 0.0));
      c.target.push_back(truth * (in_tile + Eigen::Vector2d(0.04 * matched_tile, 0.0)) + Eigen::Vector2d(noise(rng), noise(rng)));
    }
  }
  return c;
}

}  // namespace

TEST(RigidFit, RepetitivePatternIsAmbiguousUntilAPriorPicksTheRepetition) {
  const Pose2 truth(0.003, 0.001, 0.02);
  const Correspondences tiles = tiledCorrespondences(truth);
  const std::vector<Eigen::Vector2d>& target = tiles.target;
  const std::vector<Eigen::Vector2d>& source = tiles.source;
  FitSettings settings;
  settings.measure_ambiguity = true;
  const RigidEstimate blind = fitRigidTransform(target, source, settings);
  ASSERT_TRUE(blind.ok());
  EXPECT_GT(blind.ambiguity(), 0.5);  // a shifted transform is nearly as good (unique texture: near 0)
  // A prior within 1.5 cm of the truth leaves one repetition: the right one, unambiguously.
  const TransformPrior prior{Pose2(0.01, -0.005, 0.03), 0.015, 0.05};
  const RigidEstimate guided = fitRigidTransform(target, source, settings, prior);
  ASSERT_TRUE(guided.ok());
  EXPECT_LT((guided.T_target_source.translation() - truth.translation()).norm(), 0.0002);
  EXPECT_LT(guided.ambiguity(), 0.2);
  // A prior that excludes the truth finds no consistent transform.
  const TransformPrior wrong{Pose2(0.2, 0.2, 1.0), 0.015, 0.05};
  EXPECT_FALSE(fitRigidTransform(target, source, settings, wrong).ok());
}

TEST(RigidFit, MatchesThatStayedInPlaceMakeNoRival) {
  // 40 ground matches move with the robot (1.5 cm, 0.5 degree); 25 more are the robot's own artifacts (a
  // bumper's bolts, lens dirt) spread over the image, staying in place within 0.3 mm, so the zero motion
  // explains them. That rival is not a repetition of the floor.
  const Pose2 truth(0.0, -0.015, 0.5 * M_PI / 180.0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ground(-0.07, 0.07);
  std::normal_distribution<double> noise(0.0, 0.0001), jitter(0.0, 0.0003);
  std::vector<Eigen::Vector2d> target, source;
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector2d p(ground(rng), ground(rng));
    source.push_back(p);
    target.push_back(truth * p + Eigen::Vector2d(noise(rng), noise(rng)));
  }
  for (int i = 0; i < 25; ++i) {
    const Eigen::Vector2d p(ground(rng), ground(rng));
    source.push_back(p);
    target.push_back(p + Eigen::Vector2d(jitter(rng), jitter(rng)));
  }
  FitSettings settings;
  settings.measure_ambiguity = true;
  settings.rival_max_rotation_rad = 1.0 * M_PI / 180.0;  // as odometry measures it: shifted copies only
  const RigidEstimate counted = fitRigidTransform(target, source, settings);
  ASSERT_TRUE(counted.ok());
  EXPECT_GT(counted.ambiguity(), 0.5);  // the artifacts' transform rivals the motion
  settings.rival_min_motion_m = 0.0026;
  const RigidEstimate discounted = fitRigidTransform(target, source, settings);
  ASSERT_TRUE(discounted.ok());
  EXPECT_LT((discounted.T_target_source.translation() - truth.translation()).norm(), 0.0003);
  EXPECT_LT(discounted.ambiguity(), 0.1);
}

TEST(RigidFit, ARepeatedFloorStillHasARivalWhenStillMatchesAreDiscounted) {
  // Tiles moved 1 cm: their copies one tile over moved in the image, so the rival stays.
  const Correspondences tiles = tiledCorrespondences(Pose2(0.01, 0.0, 0.0));
  FitSettings settings;
  settings.measure_ambiguity = true;
  settings.rival_max_rotation_rad = 1.0 * M_PI / 180.0;
  settings.rival_min_motion_m = 0.0026;
  const RigidEstimate fit = fitRigidTransform(tiles.target, tiles.source, settings);
  ASSERT_TRUE(fit.ok());
  EXPECT_GT(fit.ambiguity(), 0.5);
}

TEST(RigidFit, TheCovarianceOfAFitOfFewMatchesStatesHowFarOffItIs) {
  // What `uncertain` frames rest on: 25 matches with 0.3 mm noise (a weak floor), 3 of them wrong, 400 times. A
  // normal error lies within one standard deviation 68% of the time and beyond three 0.3% of the time; measured:
  // 400 fits, 271 headings within one (67.8%), 1 beyond three.
  std::mt19937 rng(17);
  std::normal_distribution<double> noise(0.0, 0.0003);
  std::uniform_real_distribution<double> ux(-0.05, 0.05), uy(-0.035, 0.035);
  int fits = 0, within_one = 0, beyond_three = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Pose2 truth(0.01, 0.002 * (trial % 5), 0.1 * (trial % 7) - 0.3);
    std::vector<Eigen::Vector2d> target, source;
    for (int i = 0; i < 25; ++i) {
      const Eigen::Vector2d p(ux(rng), uy(rng));
      source.push_back(p);
      target.push_back(i < 3 ? Eigen::Vector2d(ux(rng), uy(rng)) : Eigen::Vector2d(truth * p + Eigen::Vector2d(noise(rng), noise(rng))));
    }
    FitSettings settings;
    settings.min_inliers = 10;
    const RigidEstimate fit = fitRigidTransform(target, source, settings);
    if (!fit.ok()) continue;
    ++fits;
    const double off = std::abs(wrapAngle(fit.T_target_source.theta - truth.theta)) / std::sqrt(fit.covariance(2, 2));
    within_one += off <= 1.0 ? 1 : 0;
    beyond_three += off > 3.0 ? 1 : 0;
  }
  EXPECT_GE(fits, 390);
  EXPECT_NEAR(static_cast<double>(within_one) / fits, 0.68, 0.1);
  EXPECT_LE(beyond_three, 4);
}

TEST(RigidFit, WithinAtSigmasJudgesTheHeadingAndThePositionAlongItsWorstDirection) {
  const double deg = M_PI / 180.0;
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  c(0, 0) = c(1, 1) = std::pow(0.001, 2);
  c(2, 2) = std::pow(0.16 * deg, 2);
  EXPECT_TRUE(withinAtSigmas(c, 3.0, 0.005, 0.5 * deg));   // 3 x 0.16 = 0.48 degrees, 3 mm
  c(2, 2) = std::pow(0.17 * deg, 2);
  EXPECT_FALSE(withinAtSigmas(c, 3.0, 0.005, 0.5 * deg));  // 0.51 degrees
  EXPECT_TRUE(withinAtSigmas(c, 2.0, 0.005, 0.5 * deg));
  // 1.5 mm on either axis, correlated 0.9: along the diagonal sqrt(1.9) x 1.5 = 2.07 mm, three of which exceed 5 mm.
  c(2, 2) = std::pow(0.1 * deg, 2);
  c(0, 0) = c(1, 1) = std::pow(0.0015, 2);
  EXPECT_TRUE(withinAtSigmas(c, 3.0, 0.005, 0.5 * deg));
  c(0, 1) = c(1, 0) = 0.9 * std::pow(0.0015, 2);
  EXPECT_FALSE(withinAtSigmas(c, 3.0, 0.005, 0.5 * deg));
  EXPECT_TRUE(withinAtSigmas(c, 2.0, 0.005, 0.5 * deg));  // 4.1 mm
}

TEST(RigidFit, AWeakFitsChanceRivalShowsNoRepetitionATilesRivalDoes) {
  // A weak floor: 11 matches move with the robot, 4 more agree by chance on a transform 3 cm away. That rival has
  // a third of the fit's inliers, so it is listed, but no fit of 4 inliers would be believed.
  const Pose2 truth(0.01, 0.0, 0.02), elsewhere(-0.02, 0.01, 0.0);
  const Correspondences moved = makeCorrespondences(truth, 11, 0.0, 3), chance = makeCorrespondences(elsewhere, 4, 0.0, 4);
  Correspondences weak = moved;
  weak.target.insert(weak.target.end(), chance.target.begin(), chance.target.end());
  weak.source.insert(weak.source.end(), chance.source.begin(), chance.source.end());
  FitSettings settings;
  settings.measure_ambiguity = true;
  settings.min_inliers = 8;
  const RigidEstimate fit = fitRigidTransform(weak.target, weak.source, settings);
  ASSERT_TRUE(fit.ok());
  EXPECT_LT((fit.T_target_source.translation() - truth.translation()).norm(), 0.0005);
  ASSERT_FALSE(fit.rivals.empty());
  EXPECT_EQ(fit.rival_inliers, 4);
  EXPECT_FALSE(showsARepetition(fit, 12));
  EXPECT_TRUE(showsARepetition(fit, 4));
  // Tiles: every repetition is matched, the rival one tile over has dozens of inliers.
  const Correspondences tiles = tiledCorrespondences(Pose2(0.01, 0.0, 0.0));
  const RigidEstimate tiled = fitRigidTransform(tiles.target, tiles.source, settings);
  ASSERT_TRUE(tiled.ok());
  EXPECT_GE(tiled.rival_inliers, 40);
  EXPECT_TRUE(showsARepetition(tiled, 12));
}
