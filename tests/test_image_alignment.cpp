// Odometry by aligning the images themselves where a floor gives too few keypoints (core/ImageAlignment.hpp,
// pipeline/SlamAlignment.cpp): known warps recovered, still artifacts left out, a smooth floor tracked, weak fits
// on a floor of bricks checked.
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "groundslam/core/ImageAlignment.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/pipeline/Slam.hpp"
#include "groundslam/sim/Simulator.hpp"
#include "OutdoorLook.hpp"

using namespace groundslam;

namespace {

constexpr double kDeg = M_PI / 180.0;

/// A smooth floor: seeded noise blurred to blobs `blur_px` wide, stretched to 0..255 (few corners for ORB).
/// Seeded white noise, standard deviation 1 (CV_32F, size x size), blurred `blur_px`.
cv::Mat blurredNoise(int size, double blur_px, std::uint64_t seed) {
  cv::Mat noise(size, size, CV_32F);
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  for (int r = 0; r < size; ++r) {
    for (int c = 0; c < size; ++c) noise.at<float>(r, c) = gauss(rng);
  }
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), blur_px);
  return noise;
}

cv::Mat smoothTexture(int size, double blur_px, std::uint64_t seed) {
  cv::Mat noise = blurredNoise(size, blur_px, seed);
  cv::Mat texture;
  cv::normalize(noise, noise, 0.0, 255.0, cv::NORM_MINMAX);
  noise.convertTo(texture, CV_8U);
  return texture;
}

/// A floor of bricks (`brick_px` x 2 `brick_px`, rows offset by half a brick, dark mortar 3 pixels wide, each brick
/// a little lighter or darker, faint blotches) blurred: its few corners are the mortar's, and most keypoints lie
/// on its edges.
cv::Mat brickTexture(int size, int brick_px, std::uint64_t seed) {
  cv::Mat floor = smoothTexture(size, 6.0, seed);
  floor.convertTo(floor, CV_32F, 0.18, 105.0);
  std::mt19937_64 rng(seed + 1);
  std::uniform_real_distribution<float> shade(-12.0f, 12.0f);
  std::uniform_int_distribution<int> length(3 * brick_px / 2, 5 * brick_px / 2);
  for (int top = 0; top < size; top += brick_px) {
    for (int left = -length(rng) / 2; left < size;) {
      const int brick_length = length(rng);
      const cv::Rect brick = cv::Rect(left, top, brick_length, brick_px) & cv::Rect(0, 0, size, size);
      floor(brick) += shade(rng);
      cv::rectangle(floor, brick, cv::Scalar(60.0), 3);
      left += brick_length;
    }
  }
  cv::GaussianBlur(floor, floor, cv::Size(0, 0), 2.0);
  cv::Mat texture;
  floor.convertTo(texture, CV_8U);
  return texture;
}

cv::Matx23d rigidWarp(double theta_rad, double tx, double ty) {
  return {std::cos(theta_rad), -std::sin(theta_rad), tx, std::sin(theta_rad), std::cos(theta_rad), ty};
}

/// The farthest a warp takes the corners and centre of a 320 x 240 image from where `expected` takes them.
double cornerError(const cv::Matx23d& W, const cv::Matx23d& expected) {
  double worst = 0.0;
  for (const cv::Vec3d& p : {cv::Vec3d(0, 0, 1), cv::Vec3d(319, 0, 1), cv::Vec3d(0, 239, 1), cv::Vec3d(319, 239, 1), cv::Vec3d(160, 120, 1)}) {
    worst = std::max(worst, cv::norm((W - expected) * p));
  }
  return worst;
}

/// Two 320 x 240 views of one smooth floor, the current one seen through `W_previous_current` (a current pixel x
/// shows what the previous image shows at W x); `shadow` darkens the same upper-left triangle of both, sharp-edged.
/// Two 320 x 240 views of `floor` (at least 400 x 360): the previous one its crop at (80, 120), the current one seen
/// through `W_previous_current`.
std::pair<cv::Mat, cv::Mat> viewsOf(const cv::Mat& floor, const cv::Matx23d& W_previous_current) {
  cv::Mat current;
  // Sampled from the whole floor so that no border shows: floor coordinates = W x + the crop's corner.
  cv::Matx23d W_floor = W_previous_current;
  W_floor(0, 2) += 80.0;
  W_floor(1, 2) += 120.0;
  cv::warpAffine(floor, current, W_floor, cv::Size(320, 240), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP);
  return {floor(cv::Rect(80, 120, 320, 240)).clone(), current};
}

std::pair<cv::Mat, cv::Mat> twoViews(const cv::Matx23d& W_previous_current, bool shadow) {
  auto [previous, current] = viewsOf(smoothTexture(480, 4.0, 7), W_previous_current);
  if (shadow) {
    const std::vector<cv::Point> triangle{{0, 0}, {250, 0}, {0, 190}};
    for (cv::Mat* image : {&previous, &current}) {
      cv::Mat dark = image->clone();
      dark *= 0.35;
      cv::Mat mask = cv::Mat::zeros(image->size(), CV_8U);
      cv::fillConvexPoly(mask, triangle, 255);
      dark.copyTo(*image, mask);
    }
  }
  return {previous, current};
}

}  // namespace

TEST(ImageAlignment, AKnownRigidWarpIsRecoveredFromAStartAFewPixelsOff) {
  const cv::Matx23d truth = rigidWarp(3.0 * kDeg, 14.0, -6.0);
  const auto [previous, current] = twoViews(truth, false);
  const ImageAlignmentSettings settings;
  const ImageAlignment aligned = alignImages(alignmentImage(previous, settings), alignmentImage(current, settings),
                                             {rigidWarp(2.0 * kDeg, 11.0, -3.0)}, settings);
  ASSERT_TRUE(aligned.converged);
  EXPECT_LT(cornerError(aligned.W_previous_current, truth), 0.5);  // pixels of the 320 x 240 image
  EXPECT_GT(aligned.correlation, 0.95);
  EXPECT_LT(aligned.spread_px, 0.2);
}

TEST(ImageAlignment, ASolutionIsProbedOnlyWhereItCanClearTheBarItIsJudgedBy) {
  const cv::Matx23d truth = rigidWarp(3.0 * kDeg, 14.0, -6.0);
  const auto [previous, current] = twoViews(truth, false);
  const ImageAlignmentSettings settings;
  const AlignmentImage p = alignmentImage(previous, settings), c = alignmentImage(current, settings);
  const std::vector<cv::Matx23d> start = {rigidWarp(2.0 * kDeg, 11.0, -3.0)};
  const ImageAlignment probed = alignImages(p, c, start, settings);
  ASSERT_TRUE(probed.converged);
  ASSERT_GT(probed.correlation, 0.95);
  ASSERT_GT(probed.spread_px, 0.0);
  // A bar its correlations clear: probed as without one, the very same result; cleared where the spread allows.
  const AlignmentBar clearable{0.9, 2.0, 0.001, 0.0005};  // 1 mm at 0.5 mm a pixel: 2 pixels of spread
  const ImageAlignment judged = alignImages(p, c, start, settings, clearable);
  EXPECT_EQ(judged.W_previous_current, probed.W_previous_current);
  EXPECT_EQ(judged.spread_px, probed.spread_px);
  EXPECT_TRUE(clearsBar(judged, clearable));
  AlignmentBar tight = clearable;
  tight.max_spread_m = 0.1 * probed.spread_px * tight.metres_per_px;  // a tenth of the spread the probes show
  EXPECT_FALSE(clearsBar(alignImages(p, c, start, settings, tight), tight));
  // A bar its correlation cannot clear: the same solution, not probed (spread infinite), and not believed.
  const AlignmentBar unclearable{0.999, 2.0, 0.001, 0.0005};
  const ImageAlignment refused = alignImages(p, c, start, settings, unclearable);
  EXPECT_EQ(refused.W_previous_current, probed.W_previous_current);
  EXPECT_EQ(refused.correlation, probed.correlation);
  EXPECT_TRUE(std::isinf(refused.spread_px));
  EXPECT_FALSE(clearsBar(refused, unclearable));
}

TEST(ImageAlignment, ASharpShadowFixedInTheImageDoesNotPullTheWarpToRest) {
  // The shadow's edge, the strongest edge of both images, stays put: aligned, it says "no motion".
  const cv::Matx23d truth = rigidWarp(-2.0 * kDeg, 16.0, 5.0);
  const auto [previous, current] = twoViews(truth, true);
  ImageAlignmentSettings settings;
  const AlignmentImage p = alignmentImage(previous, settings), c = alignmentImage(current, settings);
  const ImageAlignment aligned = alignImages(p, c, {rigidWarp(-1.0 * kDeg, 13.0, 2.0)}, settings);
  ASSERT_TRUE(aligned.converged);
  EXPECT_LT(cornerError(aligned.W_previous_current, truth), 0.8);
  // The still part is found: the edge's neighbourhood correlates with itself in place, the open floor does not.
  const cv::Mat moving = movingPixels(p.pixels, c.pixels, toReducedPixels(truth, p.scale), settings.still_correlation);
  EXPECT_EQ(moving.at<std::uint8_t>(49, 60), 0);      // on the shadow's edge (reduced pixels: x / 125 + y / 95 = 1)
  EXPECT_EQ(moving.at<std::uint8_t>(100, 140), 255);  // open floor, far from the edge
}

TEST(ImageAlignment, WhereOnlyTheRobotsOwnArtifactsShowTheImagesSayNothingAboutTheMotion) {
  // A floor of almost no contrast under a lamp's glare and a sharp shadow, both fixed in the image: whatever the
  // alignment finds, rest explains the images about as well (Slam refuses it: odometry.align_rest_ratio).
  const cv::Matx23d truth = rigidWarp(1.0 * kDeg, 17.0, 0.0);
  auto [previous, current] = twoViews(truth, true);
  cv::Mat glare(previous.size(), CV_32F);
  for (int r = 0; r < glare.rows; ++r) {
    for (int c = 0; c < glare.cols; ++c) glare.at<float>(r, c) = static_cast<float>(120.0 * std::exp(-((c - 110.0) * (c - 110.0) + (r - 120.0) * (r - 120.0)) / 1800.0));
  }
  for (cv::Mat* image : {&previous, &current}) {
    cv::Mat faint;
    image->convertTo(faint, CV_32F, 0.03, 60.0);  // the floor's contrast down to a few grey levels
    cv::Mat(faint + glare).convertTo(*image, CV_8U);
  }
  const ImageAlignmentSettings settings;
  const ImageAlignment aligned = alignImages(alignmentImage(previous, settings), alignmentImage(current, settings),
                                             {rigidWarp(1.0 * kDeg, 15.0, 1.0)}, settings);
  ASSERT_TRUE(aligned.converged);  // measured: correlation 0.904, at rest 0.870
  EXPECT_LT(1.0 - aligned.rest_correlation, 2.0 * (1.0 - aligned.correlation));
  // The same views with the floor's full contrast: the motion explains them far better than rest.
  const auto [p, c] = twoViews(truth, true);
  const ImageAlignment clear = alignImages(alignmentImage(p, settings), alignmentImage(c, settings), {rigidWarp(1.0 * kDeg, 15.0, 1.0)}, settings);
  ASSERT_TRUE(clear.converged);
  EXPECT_GT(1.0 - clear.rest_correlation, 5.0 * (1.0 - clear.correlation));
}

/// The warp of a turn by `theta` about the pixel `centre` (current pixel to previous).
cv::Matx23d turnAbout(const cv::Point2d& centre, double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  return {c, -s, centre.x - c * centre.x + s * centre.y, s, c, centre.y - s * centre.x - c * centre.y};
}

TEST(ImageAlignment, ATurnOnTheSpotIsFoundByItsCorrelationAndThenAligned) {
  // 80 degrees about the image centre (a turn on the spot seen by a camera above the robot's origin), far beyond
  // any start near the usual step.
  const cv::Point2d centre(160.0, 120.0);
  const cv::Matx23d truth = turnAbout(centre, 80.0 * kDeg);
  const auto [previous, current] = twoViews(truth, false);
  const ImageAlignmentSettings settings;
  const AlignmentImage p = alignmentImage(previous, settings), c = alignmentImage(current, settings);
  const std::vector<cv::Matx23d> turns = turnCandidates(p, c, centre, 5.0, 0.1);
  ASSERT_EQ(turns.size(), 1u);
  EXPECT_NEAR(std::atan2(turns.front()(1, 0), turns.front()(0, 0)), 80.0 * kDeg, 2.6 * kDeg);  // half a step
  const ImageAlignment aligned = alignImages(p, c, turns, settings);
  ASSERT_TRUE(aligned.converged);
  EXPECT_LT(cornerError(aligned.W_previous_current, truth), 0.8);
  // A floor that looks the same turned by half a turn has two such turns: which one is not known.
  cv::Mat symmetric_previous, symmetric_current;
  cv::Mat turned_previous, turned_current;
  cv::rotate(previous, turned_previous, cv::ROTATE_180);
  cv::rotate(current, turned_current, cv::ROTATE_180);
  cv::addWeighted(previous, 0.5, turned_previous, 0.5, 0.0, symmetric_previous);
  cv::addWeighted(current, 0.5, turned_current, 0.5, 0.0, symmetric_current);
  EXPECT_GE(turnCandidates(alignmentImage(symmetric_previous, settings), alignmentImage(symmetric_current, settings), centre, 5.0, 0.1).size(), 2u);
}

namespace {

/// The root mean square of an alignment image over the pixels of `mask` (reduced pixels).
double contrastOver(const AlignmentImage& image, const cv::Mat& mask) {
  cv::Scalar mean, deviation;
  cv::meanStdDev(image.pixels, mean, deviation, mask);
  return std::hypot(mean[0], deviation[0]);
}

}  // namespace

TEST(ImageAlignment, ContrastNormalisedTheGroundInTheShadowCountsAsMuchAsInTheLight) {
  const cv::Matx23d truth = rigidWarp(-2.0 * kDeg, 16.0, 5.0);
  const auto [previous, current] = twoViews(truth, true);  // the shadow keeps 35% of the light
  ImageAlignmentSettings plain, normalised;
  plain.highpass_fraction = normalised.highpass_fraction = 0.02;
  normalised.normalise_contrast = true;
  // Reduced pixels (160 x 120) well inside the shadow (x / 125 + y / 95 < 1, halved) and well in the light.
  cv::Mat shadowed = cv::Mat::zeros(120, 160, CV_8U), lit = shadowed.clone();
  cv::rectangle(shadowed, cv::Rect(5, 5, 30, 25), 255, cv::FILLED);
  cv::rectangle(lit, cv::Rect(110, 70, 40, 40), 255, cv::FILLED);
  const AlignmentImage p_plain = alignmentImage(previous, plain), p_normalised = alignmentImage(previous, normalised);
  EXPECT_LT(contrastOver(p_plain, shadowed), 0.5 * contrastOver(p_plain, lit));  // measured: 0.35 of it
  const double ratio = contrastOver(p_normalised, shadowed) / contrastOver(p_normalised, lit);
  EXPECT_GT(ratio, 0.8);
  EXPECT_LT(ratio, 1.25);
  const ImageAlignment aligned = alignImages(p_normalised, alignmentImage(current, normalised), {rigidWarp(-1.0 * kDeg, 13.0, 2.0)}, normalised);
  ASSERT_TRUE(aligned.converged);
  EXPECT_LT(cornerError(aligned.W_previous_current, truth), 0.5);
  EXPECT_EQ(aligned.rival_correlation, -1.0);  // one start: no rival
}

TEST(ImageAlignment, PixelsBlankedInTheCurrentImageDoNotPullARefinedTurnShort) {
  // Both images blank the same bands (the light's edges, fixed in the image: zeroed and out of their ground masks).
  // ECC masks only the previous image; the current image's zeros, seen through the warp, would still be compared, a
  // pattern that fits best at rest. refineAlignment leaves out the previous pixels the start puts on them.
  const cv::Matx23d truth = rigidWarp(8.0 * kDeg, 30.0, -12.0);
  const auto [previous, current] = viewsOf(smoothTexture(480, 4.0, 7), truth);
  ImageAlignmentSettings settings;
  settings.highpass_fraction = 0.02;
  settings.normalise_contrast = true;
  AlignmentImage p = alignmentImage(previous, settings), c = alignmentImage(current, settings);
  for (AlignmentImage* image : {&p, &c}) {
    image->ground = cv::Mat(image->pixels.size(), CV_8U, cv::Scalar(255));
    for (int band = 0; band < 6; ++band) {  // reduced pixels (160 x 120): six slanted bands 6 pixels wide
      cv::line(image->ground, cv::Point(20 + 26 * band, 0), cv::Point(26 * band, 119), cv::Scalar(0), 6);
    }
    image->pixels.setTo(0.0f, image->ground == 0);
  }
  const ImageAlignment refined = refineAlignment(p, c, truth, settings);
  ASSERT_TRUE(refined.converged);
  const double turn = std::atan2(refined.W_previous_current(1, 0), refined.W_previous_current(0, 0));
  // Measured: 0.006 degrees and 0.04 pixels off; with the current image's zeros compared, 0.084 degrees short and 0.37
  // pixels off.
  EXPECT_LT(std::abs(turn - 8.0 * kDeg), 0.02 * kDeg);
  EXPECT_LT(cornerError(refined.W_previous_current, truth), 0.1);
}

TEST(ImageAlignment, OnAFloorThatRepeatsAStartOneRepetitionOverEndsThereAsWellExplained) {
  // Tiles 48 pixels wide of one pattern: starts one step (12 pixels) and one tile further each find a repetition.
  const cv::Mat tile = smoothTexture(48, 2.0, 11);
  cv::Mat floor;
  cv::repeat(tile, 10, 10, floor);
  const cv::Matx23d truth = rigidWarp(0.0, 13.0, 1.0);
  const std::vector<cv::Matx23d> starts{rigidWarp(0.0, 12.0, 0.0), rigidWarp(0.0, 12.0 + 48.0, 0.0)};
  const ImageAlignmentSettings settings;
  const auto [previous, current] = viewsOf(floor, truth);
  const ImageAlignment repeated = alignImages(alignmentImage(previous, settings), alignmentImage(current, settings), starts, settings);
  ASSERT_TRUE(repeated.converged);
  EXPECT_GT(repeated.rival_correlation, repeated.correlation - 0.05);
  // A floor that does not repeat: the far start ends elsewhere, far less well explained, or at the same place.
  const auto [p, c] = viewsOf(smoothTexture(600, 2.0, 11), truth);
  const ImageAlignment unique = alignImages(alignmentImage(p, settings), alignmentImage(c, settings), starts, settings);
  ASSERT_TRUE(unique.converged);
  EXPECT_LT(cornerError(unique.W_previous_current, truth), 0.5);
  EXPECT_LT(unique.rival_correlation, 0.5 * unique.correlation);
}

TEST(ImageAlignment, WarpsConvertBetweenOriginalAndReducedPixelsExactly) {
  const cv::Matx23d W = rigidWarp(0.3, 12.5, -7.25);
  const cv::Matx23d back = toOriginalPixels(toReducedPixels(W, 4.0), 4.0);
  EXPECT_LT(cornerError(back, W), 1e-9);
  // A pure shift of 8 original pixels is 2 pixels of an image reduced 4 times.
  const cv::Matx23d shift = toReducedPixels(rigidWarp(0.0, 8.0, 0.0), 4.0);
  EXPECT_NEAR(shift(0, 2), 2.0, 1e-12);
}

namespace {

/// One lap of `frames` frames at 1 cm per frame over a user texture laid 0.6 m wide, sensor noise 2 grey levels.
sim::SimulationSettings floorRun(sim::PathKind kind, int frames, std::uint64_t seed) {
  sim::SimulationSettings s;
  s.path.kind = kind;
  s.path.frames = frames;
  s.path.laps = 1;
  s.photometry.noise_sigma = 2.0;
  s.user_texture_width_m = 0.6;
  s.seed = seed;
  return s;
}

/// A configuration for `s`'s camera, loop closure off: odometry alone.
Config odometryOnlyConfig(const sim::SimulationSettings& s) {
  Config config;
  config.camera = cameraConfigOf(s.camera, s.mounting_height_m);
  config.loop_closure.enabled = false;
  return config;
}

/// How far frame i's odometry motion is from the true one: metres, radians.
std::pair<double, double> odometryError(const FrameResult& r, const sim::SequenceSimulator& simulator, int i) {
  const Pose2 expected = between(simulator.groundTruth()[size_t(i - 1)], simulator.groundTruth()[size_t(i)]);
  return {(r.odometry.translation() - expected.translation()).norm(), std::abs(wrapAngle(r.odometry.theta - expected.theta))};
}

struct SmoothFloorRun {
  int measured = 0, aligned = 0, failed = 0, lost = 0;
  int relocalized_at = -1;
  double worst_aligned_m = 0.0, worst_aligned_rad = 0.0, mean_aligned_rad = 0.0;
  double ate_m = 0.0;
};

/// A loop on a smooth floor (blobs 3 cm wide, 18 x 14 cm footprint), 1 cm per frame: odometry alone, or with
/// loop closure and frame `blank` covered (a blank image: tracking is lost there).
SmoothFloorRun runSmoothFloor(bool align_images, bool loop_closure = false, int blank = -1) {
  sim::SimulationSettings s = floorRun(sim::PathKind::loop, 60, 5);
  const sim::SequenceSimulator simulator(s, smoothTexture(512, 12.0, 11));
  Config config = odometryOnlyConfig(s);
  config.loop_closure.enabled = loop_closure;
  config.odometry_checks.align_images = align_images;
  Slam slam(config, loop_closure ? std::make_shared<const Vocabulary>(readVocabulary(std::string(GROUNDSLAM_SOURCE_DIR) +
                                                                                     "/config/vocabulary/ground.gslmvoc"))
                                 : nullptr);
  SmoothFloorRun run;
  Trajectory truth;
  for (int i = 0; i < simulator.frameCount(); ++i) {
    const cv::Mat image = i == blank ? cv::Mat(simulator.renderFrame(i).size(), CV_8U, cv::Scalar(128)) : simulator.renderFrame(i);
    const FrameResult r = slam.process(image, i);
    if (i != blank) truth.push_back({static_cast<double>(i), simulator.groundTruth()[size_t(i)]});
    run.lost += r.status == FrameStatus::lost ? 1 : 0;
    if (r.status == FrameStatus::relocalized && run.relocalized_at < 0) run.relocalized_at = i;
    if (i == 0) continue;
    run.measured += measuredByOdometry(r.status) ? 1 : 0;
    run.failed += r.status == FrameStatus::fallback ? 1 : 0;
    if (r.status != FrameStatus::aligned) continue;
    ++run.aligned;
    const auto [off_m, off_rad] = odometryError(r, simulator, i);
    run.worst_aligned_m = std::max(run.worst_aligned_m, off_m);
    run.worst_aligned_rad = std::max(run.worst_aligned_rad, off_rad);
    run.mean_aligned_rad += off_rad;
  }
  run.mean_aligned_rad /= std::max(1, run.aligned);
  slam.finish();
  run.ate_m = evaluateTrajectory(truth, slam.trajectory()).metrics.ate_rmse_m;
  return run;
}

}  // namespace

struct WeakFitRun {
  int ok = 0, ok_off = 0, aligned = 0, aligned_off = 0, unconfirmed = 0, unconfirmed_off = 0, uncertain = 0, uncertain_off = 0;
  double ok_heading_error_rad = 0.0;        ///< summed over ok frames
  double measured_heading_error_rad = 0.0;  ///< summed over ok and aligned frames
};

/// Odometry alone on a floor of bricks, 1 cm per frame; a fit with fewer than `check_below` inliers is checked;
/// `ok_sigmas` > 0: a frame is `ok` only if its fit's covariance vouches for it (OdometryChecks::ok_sigmas).
WeakFitRun runBrickFloor(int check_below, sim::PathKind path, std::uint64_t seed, bool outdoors = false, double ok_sigmas = 0.0) {
  sim::SimulationSettings s = floorRun(path, 120, seed);
  if (outdoors) s.artifacts = {0.6, 6, 0.8, 0.15};
  const sim::SequenceSimulator simulator(s, brickTexture(512, 24, seed));
  Config config = odometryOnlyConfig(s);
  config.odometry_checks.align_check_below_inliers = check_below;
  config.odometry_checks.ok_sigmas = ok_sigmas;
  Slam slam(config, nullptr);
  WeakFitRun run;
  for (int i = 0; i < simulator.frameCount(); ++i) {
    const FrameResult r = slam.process(simulator.renderFrame(i), i);
    if (i == 0) continue;
    const auto [off_m, off_rad] = odometryError(r, simulator, i);
    const bool off = off_m > 0.005 || off_rad > 0.5 * kDeg;
    if (r.status == FrameStatus::ok) {
      ++run.ok;
      run.ok_off += off ? 1 : 0;
      run.ok_heading_error_rad += off_rad;
    } else if (r.status == FrameStatus::aligned) {
      ++run.aligned;
      run.aligned_off += off ? 1 : 0;
    } else if (r.status == FrameStatus::unconfirmed) {
      ++run.unconfirmed;
      run.unconfirmed_off += off ? 1 : 0;
    } else if (r.status == FrameStatus::uncertain) {
      ++run.uncertain;
      run.uncertain_off += off ? 1 : 0;
    }
    if (r.status == FrameStatus::ok || r.status == FrameStatus::aligned || r.status == FrameStatus::uncertain) {
      run.measured_heading_error_rad += off_rad;
    }
  }
  return run;
}

TEST(ImageAlignment, OnABrickFloorAFitTheImagesContradictAndTheMatchesCannotTellGivesWayToTheAlignment) {
  // Loops on two floors of blurred bricks: most keypoints lie on mortar lines, and a fit of a few dozen of them can
  // be half a degree off. Checked by the images (fits under 60 inliers), such frames say `aligned` with the
  // images' motion. Measured, without / with the check: ok frames off by 5 mm or 0.5 degrees 4 / 0; aligned frames
  // 26 / 45, none off; heading error summed over the ok and aligned frames 31.1 / 22.1 degrees.
  int ok_off_without = 0, ok_off_with = 0, aligned_off_with = 0, aligned_with = 0, aligned_without = 0;
  double heading_without = 0.0, heading_with = 0.0;
  for (const std::uint64_t seed : {5u, 8u}) {
    const WeakFitRun without = runBrickFloor(0, sim::PathKind::loop, seed);
    const WeakFitRun with = runBrickFloor(60, sim::PathKind::loop, seed);
    ok_off_without += without.ok_off;
    ok_off_with += with.ok_off;
    aligned_without += without.aligned;
    aligned_with += with.aligned;
    aligned_off_with += with.aligned_off;
    heading_without += without.measured_heading_error_rad;
    heading_with += with.measured_heading_error_rad;
  }
  EXPECT_GE(ok_off_without, 2);
  EXPECT_EQ(ok_off_with, 0);
  EXPECT_GE(aligned_with, aligned_without + 10);
  EXPECT_EQ(aligned_off_with, 0);
  EXPECT_LT(heading_with, 0.85 * heading_without);
}

TEST(ImageAlignment, OutdoorsOnABrickFloorAFitOfFewInliersTheImagesDoNotConfirmIsFlaggedUnconfirmed) {
  // The same floors with the robot's shadow, lens dirt, a lamp's glare and a bumper in view: the bricks' few
  // keypoints compete with the artifacts' and many fits are over half a degree off. A fit of under 30 inliers the
  // images do not confirm says `unconfirmed`. Measured, without / with the check (seeds 8 and 13): ok frames off
  // 15 + 22 / 0 + 3; unconfirmed frames 29 + 39, of them off 15 + 20.
  int ok_off_without = 0, ok_off_with = 0, unconfirmed = 0, unconfirmed_off = 0;
  for (const std::uint64_t seed : {8u, 13u}) {
    const WeakFitRun without = runBrickFloor(0, sim::PathKind::loop, seed, true);
    const WeakFitRun with = runBrickFloor(60, sim::PathKind::loop, seed, true);
    EXPECT_EQ(without.unconfirmed, 0);
    ok_off_without += without.ok_off;
    ok_off_with += with.ok_off;
    unconfirmed += with.unconfirmed;
    unconfirmed_off += with.unconfirmed_off;
  }
  EXPECT_GE(ok_off_without, 25);
  EXPECT_LE(ok_off_with, 6);
  EXPECT_GE(unconfirmed_off, 25);
  EXPECT_GE(unconfirmed, unconfirmed_off);
}

TEST(ImageAlignment, OutdoorsOnABrickFloorAFitWhoseCovarianceAllowsMoreThanTheToleranceSaysUncertain) {
  // The same outdoor brick floors: of the fits the images confirm, a few are still over half a degree off, and
  // their covariance says they may be. With ok_sigmas 3 (the default) such frames say `uncertain`; the label
  // changes, not the motion. Measured, ok_sigmas 0 / 3 (seeds 8 and 13): ok frames 37 / 7, of them off 3 / 0;
  // uncertain frames 30, of them off 3.
  int ok_off_without = 0, ok_off_with = 0, uncertain = 0, uncertain_off = 0, ok_with = 0;
  for (const std::uint64_t seed : {8u, 13u}) {
    const WeakFitRun without = runBrickFloor(60, sim::PathKind::loop, seed, true, 0.0);
    const WeakFitRun with = runBrickFloor(60, sim::PathKind::loop, seed, true, 3.0);
    EXPECT_EQ(without.uncertain, 0);
    EXPECT_DOUBLE_EQ(with.measured_heading_error_rad, without.measured_heading_error_rad);  // the same motions
    EXPECT_EQ(with.ok + with.uncertain, without.ok);
    ok_off_without += without.ok_off;
    ok_off_with += with.ok_off;
    ok_with += with.ok;
    uncertain += with.uncertain;
    uncertain_off += with.uncertain_off;
  }
  EXPECT_GE(ok_off_without, 2);
  EXPECT_EQ(ok_off_with, 0);
  EXPECT_EQ(uncertain_off, ok_off_without);  // every one of them, and
  EXPECT_GE(ok_with, 4);                     // not every frame
  // 36 since odometry.speed_change_frames (30 without it): frames that said `gap` for a usual step learnt wrong
  // are judged by their covariance now; 42 since the images align from the usual steps where a weak fit is not
  // confirmed (the motions they measure change the usual steps later frames are judged by).
  EXPECT_LE(uncertain, 44);
}

TEST(ImageAlignment, OnASmoothFloorTheImagesAreAlignedWhereTheFeaturesFail) {
  const SmoothFloorRun without = runSmoothFloor(false);
  const SmoothFloorRun with = runSmoothFloor(true);
  // Without the alignment the features fail on many frames (each assumed, not measured) ...
  EXPECT_GE(without.failed, 10);
  // ... with it, those frames are measured by the alignment, each within 2.5 mm and 2 degrees, 0.5 degrees on
  // average (measured: 2.3 mm, 1.85 degrees, 0.42 degrees; every frame is aligned on this floor). Without the
  // check that still parts match better in place than where the motion puts them, a smooth floor's gradients
  // were taken for still ones: every frame 2-6 mm and up to 3.2 degrees off.
  EXPECT_EQ(with.failed, 0);
  EXPECT_EQ(with.aligned + with.measured, 59);
  EXPECT_GE(with.aligned, without.failed);
  EXPECT_LT(with.worst_aligned_m, 0.0025);
  EXPECT_LT(with.worst_aligned_rad, 2.0 * kDeg);
  EXPECT_LT(with.mean_aligned_rad, 0.5 * kDeg);
}

TEST(ImageAlignment, OnASmoothFloorTrackingLostAtABlankFrameIsBridgedToTheLastTrackedFrame) {
  // Global localization needs features a smooth floor does not give: without the alignment, the robot stays lost
  // after a covered frame; with it, frame 31 is aligned with frame 29 (two usual steps) and the segment joins.
  const SmoothFloorRun without = runSmoothFloor(false, true, 30);
  const SmoothFloorRun with = runSmoothFloor(true, true, 30);
  EXPECT_LT(without.relocalized_at, 0);
  EXPECT_EQ(with.relocalized_at, 31);
  EXPECT_LE(with.lost, 1);
  // The break costs nothing against the same run without it (measured: ATE 9.5 mm against 9.7 mm; the aligned
  // motions' heading noise, 0.4 degrees a frame, is what a floor without loop closures keeps).
  const SmoothFloorRun unbroken = runSmoothFloor(true, true);
  EXPECT_LT(with.ate_m, unbroken.ate_m + 0.001);
  EXPECT_LT(unbroken.ate_m, 0.012);
}

namespace {

/// Odometry alone (no loop closure) over a faint smooth floor (blobs `blur_px` texture pixels wide at a tenth of the
/// contrast) under the outdoor look, the robot driving a 40-frame lawnmower lane at 1 cm per frame: every frame's result.
std::vector<FrameResult> faintFloorRun(double blur_px) {
  sim::SimulationSettings s = floorRun(sim::PathKind::lawnmower, 40, 5);
  s.artifacts = {0.6, 6, 0.8, 0.15};
  cv::Mat floor;
  smoothTexture(512, blur_px, 5).convertTo(floor, CV_8U, 0.1, 128.0 * 0.9);
  const sim::SequenceSimulator simulator(s, floor);
  Config config = odometryOnlyConfig(s);
  Slam slam(config, nullptr);
  std::vector<FrameResult> results;
  for (int i = 0; i < simulator.frameCount(); ++i) results.push_back(slam.process(simulator.renderFrame(i), i));
  return results;
}

}  // namespace

TEST(ImageAlignment, AFitAtRestOnAFloorTheRobotsArtifactsOutnumberIsNotConfirmedByTheImages) {
  // A faint smooth floor (blobs 1.2 and 1.4 cm wide at a tenth of the contrast) under the outdoor look, the robot
  // driving 1 cm per frame: the shadow edge, lens dirt and bumper outnumber the ground's keypoints, fits say the
  // robot stood still, and aligning the images from rest ends at rest too. The images cannot confirm such a fit
  // (their check leaves out what stays still where the fit moves the ground, and at rest nothing): under 30
  // inliers it says `unconfirmed`. Measured without this rule: of 23 + 26 such fits, 20 + 21 said `ok`; with it
  // 25 + 27, none `ok`. (Fits at rest on 30 or more inliers are `ok` once the robot was seen moving: docs/accuracy.md,
  // Sessions 17 and 28.) Run on the second floor alone (blobs 12 texels wide), to keep the test's time down.
  int weak_rest = 0, weak_rest_ok = 0, weak_rest_unconfirmed = 0;
  for (const FrameResult& r : faintFloorRun(12.0)) {
    if (r.index == 0 || r.odometry.translation().norm() > 0.001 || r.inliers >= 30 || !measuredByOdometry(r.status)) continue;
    ++weak_rest;  // the robot drove 1 cm
    weak_rest_ok += r.status == FrameStatus::ok ? 1 : 0;
    weak_rest_unconfirmed += r.status == FrameStatus::unconfirmed ? 1 : 0;
  }
  EXPECT_GE(weak_rest, 20);
  EXPECT_EQ(weak_rest_ok, 0);
  EXPECT_EQ(weak_rest_unconfirmed, weak_rest);
}

TEST(ImageAlignment, OnAFaintFloorAFitAtRestIsNotOkBeforeTheRobotWasSeenMoving) {
  // The same faint floors with fits at rest on 30 or more inliers, which the images are not asked to confirm: the
  // robot's shadow edge, lens dirt and bumper lock the fit at rest at the start, before anything has shown what stays
  // still in the image. Until some fit moved its matches, a fit at rest is not `ok`.
  int rest_before_moving = 0, rest_before_moving_ok = 0, strong = 0;
  for (const double blur : {8.0, 10.0}) {  // blobs 6 texels wide were left out for time: 3 strong fits of 39
    bool moved = false;
    for (const FrameResult& r : faintFloorRun(blur)) {
      if (r.index == 0 || !measuredByOdometry(r.status)) continue;
      const bool at_rest = r.odometry.translation().norm() < 0.001;  // the robot drove 1 cm
      if (!at_rest) moved = true;
      if (at_rest && !moved) {
        ++rest_before_moving;
        rest_before_moving_ok += r.status == FrameStatus::ok ? 1 : 0;
        strong += r.inliers >= 30 ? 1 : 0;
      }
    }
  }
  // Measured: all 2 x 39 fits are at rest (each run locks at rest from its start); 12 + 14 of them on 30 or more
  // inliers, which said `ok` before this rule.
  EXPECT_GE(rest_before_moving, 70);
  EXPECT_GE(strong, 20);
  EXPECT_EQ(rest_before_moving_ok, 0);
}

TEST(ImageAlignment, ARobotStandingStillIsOkOnceItWasSeenMoving) {
  // The same image twice is a robot standing still. At the start of the run that cannot be told from a fit locked at
  // rest by the robot's own artifacts: `uncertain`. Once it has driven, standing still is `ok` again.
  sim::SimulationSettings s;
  s.path.kind = sim::PathKind::loop;
  s.path.frames = 12;
  s.photometry.noise_sigma = 2.0;
  const sim::SequenceSimulator simulator(s);
  Config config = odometryOnlyConfig(s);
  Slam slam(config, nullptr);
  double t = 0.0;
  slam.process(simulator.renderFrame(0), t);
  const FrameResult still_at_start = slam.process(simulator.renderFrame(0), t += 0.1);
  EXPECT_EQ(still_at_start.statusName(), "uncertain");
  EXPECT_LT(still_at_start.odometry.translation().norm(), 1e-4);
  for (int i = 1; i < simulator.frameCount(); ++i) {
    const FrameResult r = slam.process(simulator.renderFrame(i), t += 0.1);
    EXPECT_EQ(r.statusName(), "ok") << i;
    EXPECT_GT(r.odometry.translation().norm(), 0.005) << i;
  }
  const FrameResult still_later = slam.process(simulator.renderFrame(simulator.frameCount() - 1), t += 0.1);
  EXPECT_EQ(still_later.statusName(), "ok");
  EXPECT_LT(still_later.odometry.translation().norm(), 1e-4);
}

namespace {

/// A faint floor: fine grain (seeded noise blurred 0.7 texels) of `contrast` grey levels around 90 (a smooth concrete
/// seen through a dim light).
cv::Mat faintTexture(int size, double contrast, std::uint64_t seed) {
  const cv::Mat noise = blurredNoise(size, 0.7, seed);
  cv::Scalar mean, deviation;
  cv::meanStdDev(noise, mean, deviation);
  cv::Mat texture;
  noise.convertTo(texture, CV_8U, contrast / deviation[0], 90.0 - contrast * mean[0] / deviation[0]);
  return texture;
}

struct FaintFloorRun {
  int measured = 0, measured_at_rest = 0, ok_off = 0, aligned = 0, aligned_off = 0, aligned_at_rest = 0, still = 0, still_near_truth = 0;
  double aligned_turn_error_rad = 0.0;  ///< summed over the aligned frames
};

/// A faint floor's run outdoors (the robot's shadow, lens dirt, a lamp's glare, a bumper, a rocking mount), dry, at 1 cm
/// per frame.
sim::SimulationSettings faintFloorOutdoors(sim::PathKind path, int frames, std::uint64_t seed) {
  sim::SimulationSettings s = floorRun(path, frames, seed);
  groundslam::testing::putUnderTheOutdoorLook(s);
  s.wet_after = 1.0;
  return s;
}

/// The vocabulary shipped with the project (loop closure and relocalization).
std::shared_ptr<const Vocabulary> groundVocabulary() {
  return std::make_shared<const Vocabulary>(readVocabulary(std::string(GROUNDSLAM_SOURCE_DIR) + "/config/vocabulary/ground.gslmvoc"));
}

/// Odometry alone, outdoors over a faint floor of `contrast` grey levels (faintFloorOutdoors); `check_rest`:
/// odometry.rest_check_by_spectra.
FaintFloorRun runFaintFloor(bool check_rest, std::uint64_t seed, double contrast = 3.0, double min_step_share = 0.5,
                            sim::PathKind path = sim::PathKind::lawnmower, int frames = 60) {
  const sim::SimulationSettings s = faintFloorOutdoors(path, frames, seed);
  const sim::SequenceSimulator simulator(s, faintTexture(512, contrast, seed));
  Config config = odometryOnlyConfig(s);
  config.odometry_checks.rest_check_by_spectra = check_rest;
  config.odometry_checks.align_min_step_share = min_step_share;
  Slam slam(config, nullptr);
  FaintFloorRun run;
  for (int i = 0; i < simulator.frameCount(); ++i) {
    const FrameResult r = slam.process(simulator.renderFrame(i), i);
    if (i == 0) continue;
    const auto [off_m, off_rad] = odometryError(r, simulator, i);
    const bool at_rest = r.odometry.translation().norm() < 0.002;  // the robot drove 1 cm
    if (measuredByOdometry(r.status)) {
      ++run.measured;
      run.measured_at_rest += at_rest ? 1 : 0;
    }
    run.ok_off += r.status == FrameStatus::ok && (off_m > 0.005 || off_rad > 0.5 * kDeg) ? 1 : 0;
    if (r.status == FrameStatus::aligned) {
      run.aligned_turn_error_rad += r.odometry.theta - between(simulator.groundTruth()[size_t(i - 1)], simulator.groundTruth()[size_t(i)]).theta;
      ++run.aligned;
      run.aligned_off += off_m > 0.005 || off_rad > 0.5 * kDeg ? 1 : 0;
      run.aligned_at_rest += at_rest ? 1 : 0;
    }
    if (r.status == FrameStatus::fallback && r.fallback_reason == FitStatus::still) {
      ++run.still;
      run.still_near_truth += off_m < 0.003 ? 1 : 0;
    }
  }
  return run;
}

}  // namespace

TEST(ImageAlignment, OutdoorsOnAFaintFloorMatchesThatAllStayInPlaceAreRefutedByTheSpectra) {
  // A floor too faint for its own keypoints to match: the robot's shadow edge, lens dirt and bumper are all that
  // match, and the fits put the robot at rest while it drives 1 cm a frame. The images measure most steps (the heading
  // images see the ground where the reduced ones see the artifacts); the fits at rest they do not replace are
  // refuted by the images' spectra, less the mean of the recent images, which see the ground shift: the images are
  // aligned from the spectra's motion, else the motion is not known (`fallback_still`). Measured (seeds 3 and 4),
  // without / with the check: measured frames at rest 7 + 7 / 1 + 1 (the first frame, before there is a mean of recent
  // images); aligned frames 103 / 112, at rest 1 / 0; still frames 0 / 3, all within 3 mm of the truth. (Before the
  // heading images measured the steps: at rest 43 + 36 / 1 + 1, still frames 0 / 104.)
  // The run without the check is made on seed 3 alone (7 at rest), to keep the test's time down.
  const FaintFloorRun without = runFaintFloor(false, 3);
  FaintFloorRun with;
  for (const std::uint64_t seed : {3u, 4u}) {
    const FaintFloorRun b = runFaintFloor(true, seed);
    with.measured_at_rest += b.measured_at_rest, with.aligned_at_rest += b.aligned_at_rest, with.ok_off += b.ok_off;
    with.still += b.still, with.still_near_truth += b.still_near_truth, with.aligned += b.aligned;
  }
  EXPECT_GE(without.measured_at_rest, 5);
  EXPECT_EQ(without.still, 0);
  EXPECT_LE(with.measured_at_rest, 2);
  EXPECT_EQ(with.aligned_at_rest, 0);
  EXPECT_EQ(with.ok_off, 0);
  EXPECT_GE(with.aligned, 100);
  EXPECT_GE(with.still, 1);
  EXPECT_EQ(with.still_near_truth, with.still);
}

TEST(ImageAlignment, OnAFaintFloorTheImagesMeasureTheStepsNeitherLeavingTheRobotBehindNorTurningShort) {
  // A faint floor a little less faint (5 grey levels), with the robot's artifacts: where the keypoints fail, the images
  // are aligned, and what stays in them pulls the alignment toward rest, turned or not. An alignment that moves the
  // robot less than half its usual step, or than a still feature's radius, is not believed
  // (odometry.align_min_step_share). Measured (loops of 100 frames, seeds 3 and 6), without / with: aligned frames
  // 97 + 74 / 95 + 74, off by 5 mm or 0.5 degrees 10 + 1 / 0. (Before the heading images measured the steps: aligned
  // frames 29 + 18 / 1 + 0, off 28 + 18 / 0.)
  // Their turns are not short: the heading images less the mean of the recent ones (what stays in the image) turn
  // -0.006 degrees from the truth on average, where without taking it away they turned -0.020 (seeds 3 and 6: -0.023
  // and -0.017) of the 3.6 degrees a frame.
  // The run without the rule is made on seed 3 alone (10 off), to keep the test's time down.
  const int aligned_off_without = runFaintFloor(true, 3, 5.0, 0.0, sim::PathKind::loop, 100).aligned_off;
  int aligned_off_with = 0, aligned_with = 0;
  double turn_error_rad = 0.0;
  for (const std::uint64_t seed : {3u, 6u}) {
    const FaintFloorRun with = runFaintFloor(true, seed, 5.0, 0.5, sim::PathKind::loop, 100);
    aligned_off_with += with.aligned_off;
    aligned_with += with.aligned;
    turn_error_rad += with.aligned_turn_error_rad;
  }
  EXPECT_GE(aligned_off_without, 8);
  EXPECT_EQ(aligned_off_with, 0);
  EXPECT_GE(aligned_with, 150);
  EXPECT_LT(std::abs(turn_error_rad / std::max(1, aligned_with)), 0.012 * kDeg);
}

namespace {

struct FirstFramesRun {
  int first_lost = 0;       ///< frames 1..4 lost (the map started again after them)
  int first_measured = 0;   ///< frames 0..4 measured in the final trajectory
  double worst_heading_rad = 0.0;  ///< over the run, every pose anchored at frame 0 as the tables do
  int bridges = 0;                 ///< graph edges over a loss (bridges and relocalizations)
  double worst_bridge_m = 0.0, worst_bridge_rad = 0.0;
};

/// Full SLAM (loop closure on) outdoors over a faint floor of `contrast` grey levels, frame `blank` covered (a blank
/// image): how the run's first frames end, and how far the edges over a loss are from the truth.
FirstFramesRun runFaintFloorStart(std::uint64_t seed, double contrast, int frames, bool measure_given_up, int blank = -1) {
  const sim::SimulationSettings s = faintFloorOutdoors(sim::PathKind::loop, frames, seed);
  const sim::SequenceSimulator simulator(s, faintTexture(512, contrast, seed));
  Config config = odometryOnlyConfig(s);
  config.loop_closure.enabled = true;
  config.odometry_checks.measure_given_up_frames = measure_given_up;
  Slam slam(config, groundVocabulary());
  FirstFramesRun run;
  for (int i = 0; i < simulator.frameCount(); ++i) {
    const cv::Mat image = i == blank ? cv::Mat(simulator.renderFrame(i).size(), CV_8U, cv::Scalar(128)) : simulator.renderFrame(i);
    const FrameResult r = slam.process(image, i);
    if (i >= 1 && i <= 4 && r.status == FrameStatus::lost) ++run.first_lost;
  }
  for (const GraphEdge& e : slam.graph().edges()) {
    if (!e.loop) continue;
    const Pose2 truth = between(simulator.groundTruth()[size_t(e.from)], simulator.groundTruth()[size_t(e.to)]);
    ++run.bridges;
    run.worst_bridge_m = std::max(run.worst_bridge_m, (e.T_from_to.translation() - truth.translation()).norm());
    run.worst_bridge_rad = std::max(run.worst_bridge_rad, std::abs(wrapAngle(e.T_from_to.theta - truth.theta)));
  }
  slam.finish();
  const Trajectory estimate = slam.trajectory();
  const double anchor = simulator.groundTruth()[0].theta - estimate[0].T_world_robot.theta;
  for (size_t i = 0; i < estimate.size(); ++i) {
    if (i <= 4 && estimate[i].measured) ++run.first_measured;
    run.worst_heading_rad = std::max(run.worst_heading_rad, std::abs(wrapAngle(estimate[i].T_world_robot.theta + anchor - simulator.groundTruth()[i].theta)));
  }
  return run;
}

}  // namespace

TEST(ImageAlignment, OnAFaintFloorABridgeTheSpectraFoundIsMeasuredByTheImagesAlignedFromIt) {
  // The faint floor outdoors, frame 20 covered: the features cannot bridge the loss, the images' spectra can (frame
  // 21, confirmed by frame 22). The spectra find the turn in half-degree bins and, on this floor, up to 1.5 degrees
  // off; the heading images aligned from there measure it. Measured (seeds 3 and 6), the bridges' worst heading error
  // without / with the alignment: 1.453 and 0.547 / 0.055 and 0.032 degrees.
  for (const std::uint64_t seed : {3u, 6u}) {
    const FirstFramesRun run = runFaintFloorStart(seed, 5.0, 30, true, 20);
    EXPECT_GE(run.bridges, 2) << seed;
    EXPECT_LT(run.worst_bridge_m, 0.005) << seed;
    EXPECT_LT(run.worst_bridge_rad, 0.2 * kDeg) << seed;
  }
}

TEST(ImageAlignment, OnAFaintFloorTheFirstFramesGivenUpAreMeasuredOnceTheStepIsKnownAndTheRunIsNotTurnedByThem) {
  // A faint floor outdoors (5 grey levels; loops of 30 frames, 3.6 degrees a frame): frame 1 cannot be measured
  // (no usual step to start the alignment from, no mean of the heading images to take what stays in the image away)
  // and the map starts again after it. The first pose anchors the world frame: the motion guessed over the given-up
  // frame turned the whole run. Measured (seeds 3 and 6) without / with measuring it again at frame 10: frames 0-4
  // measured 4 + 4 / 5 + 5; the worst heading along the run, anchored at frame 0, 12.4 + 13.9 / 0.45 + 1.6 degrees.
  for (const std::uint64_t seed : {3u, 6u}) {
    const FirstFramesRun without = runFaintFloorStart(seed, 5.0, 30, false), with = runFaintFloorStart(seed, 5.0, 30, true);
    EXPECT_GE(with.first_lost, 1) << seed;  // the case this is about: the map started again
    EXPECT_EQ(without.first_measured, 4) << seed;
    EXPECT_GT(without.worst_heading_rad, 5.0 * kDeg) << seed;
    EXPECT_EQ(with.first_measured, 5) << seed;
    EXPECT_LT(with.worst_heading_rad, 2.0 * kDeg) << seed;
  }
}

namespace {

/// The held-out outdoor carpet lawnmower of seed 313 in the texture matrix (scripts/texture_matrix.sh, condition
/// outdoor): the robot's shadow, lens dirt, glare and bumper, a rocking and bouncing mount, a quarter turn every 80
/// frames, frames dropped without a trace. Its kept frames up to `watched`; that frame's result and its true motion
/// from the kept frame before it.
struct DroppedFramesRun {
  FrameResult watched;
  Pose2 true_motion;
};

DroppedFramesRun runHeldOutCarpetLawnmower(bool gap_by_spectra, int watched) {
  sim::SimulationSettings s;
  s.texture_kind = "carpet";
  s.path.kind = sim::PathKind::lawnmower;
  s.path.frames = 400;
  s.path.lane_spacing_m = 0.6 * s.mounting_height_m * s.camera.height / s.camera.fy;
  s.seed = 313;
  groundslam::testing::putUnderTheOutdoorLook(s);
  s.motion.spin_every = 80;
  const sim::SequenceSimulator simulator(s);
  const std::vector<bool> dropped = sim::droppedFrames(simulator.frameCount(), 0.01, 6, s.seed);
  Config config = odometryOnlyConfig(s);
  config.odometry_checks.gap_by_spectra = gap_by_spectra;
  Slam slam(config, nullptr);
  DroppedFramesRun run;
  int kept = 0, previous_kept = -1;
  for (int i = 0; i < simulator.frameCount() && kept <= watched; ++i) {
    if (dropped[size_t(i)]) continue;
    const FrameResult r = slam.process(simulator.renderFrame(i), kept);
    if (kept == watched) {
      run.watched = r;
      run.true_motion = between(simulator.groundTruth()[size_t(previous_kept)], simulator.groundTruth()[size_t(i)]);
    }
    previous_kept = i;
    ++kept;
  }
  return run;
}

}  // namespace

TEST(ImageAlignment, OverFramesDroppedWithoutATraceThePairTooFewFeaturesMatchIsMeasuredNearTheSpectrasMotion) {
  // Seven frames' motion at once (six dropped): the images overlap by less than half, along the image's short side,
  // the rest under the robot's shadow, glare and bumper. Among all features the ratio test leaves 17 matches, 12
  // agreeing: tracking was lost there, and on this floor (a lane already mapped beside it, seen turned half a turn)
  // not found again for 158 frames. The images' spectra register the ground 7 cm on (no longer read as their alias
  // the other way, 6.6 cm back: SpectralTurn); features compared only near that motion measure it.
  const DroppedFramesRun without = runHeldOutCarpetLawnmower(false, 213);
  const DroppedFramesRun with = runHeldOutCarpetLawnmower(true, 213);
  EXPECT_NEAR(with.true_motion.translation().norm(), 0.07, 0.002);
  EXPECT_FALSE(measuredByOdometry(without.watched.status) || without.watched.status == FrameStatus::low_overlap) << without.watched.statusName();
  EXPECT_EQ(with.watched.status, FrameStatus::low_overlap) << with.watched.statusName();
  EXPECT_LT((with.watched.odometry.translation() - with.true_motion.translation()).norm(), 0.005);
  EXPECT_LT(std::abs(wrapAngle(with.watched.odometry.theta - with.true_motion.theta)), 0.5 * kDeg);
}

TEST(ImageAlignment, OnASmoothFloorABridgeThatTurnsTheRobotButLeavesItInPlaceIsNotBelieved) {
  // The smooth floor's loop, frame 30 covered. Frames 31-34 show frame 29's image turned by 6 degrees more each
  // (about the image centre): what an alignment pulled to rest by the robot's own shadow,
  // dirt and bumper says while the robot drives on (OpenArena's darker concrete outdoors: 17 such bridges, each
  // turned right and 17-84 mm off). An aligned bridge must move the robot by half its usual step per frame bridged,
  // as odometry's alignments must (odometry.align_min_step_share), or turn it sharply. Measured without that rule:
  // frames 31 and 33 joined the map with edges 0.2 mm long (29 -> 31, 31 -> 33; the robot drove 2 cm each).
  sim::SimulationSettings s = floorRun(sim::PathKind::loop, 60, 5);
  const sim::SequenceSimulator simulator(s, smoothTexture(512, 12.0, 11));
  Config config = odometryOnlyConfig(s);
  config.loop_closure.enabled = true;
  Slam slam(config, groundVocabulary());
  const cv::Mat seen = simulator.renderFrame(29);
  std::vector<FrameStatus> status;
  for (int i = 0; i < 40; ++i) {
    cv::Mat image = simulator.renderFrame(i);
    if (i == 30) image = cv::Mat(image.size(), CV_8U, cv::Scalar(128));
    if (i >= 31 && i <= 34) {
      const cv::Mat turn = cv::getRotationMatrix2D(cv::Point2f(0.5f * float(seen.cols), 0.5f * float(seen.rows)), 6.0 * (i - 30), 1.0);
      cv::warpAffine(seen, image, turn, seen.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
    }
    status.push_back(slam.process(image, i).status);
  }
  EXPECT_EQ(status[30], FrameStatus::lost);
  for (int i = 31; i <= 34; ++i) EXPECT_NE(status[size_t(i)], FrameStatus::relocalized) << i;
  for (const GraphEdge& e : slam.graph().edges()) EXPECT_FALSE(e.from <= 29 && e.to >= 31 && e.to <= 34) << e.from << " -> " << e.to;
}

namespace {

/// Odometry alone over the faint floor outdoors (`contrast` grey levels), frames `first_dropped` .. `first_dropped` +
/// `dropped` - 1 left out without a trace in the timestamps; with `spin_every`, sharp turns of 90 degrees. The frame
/// after the drop, and its true motion from the frame before it.
struct DroppedOnAFaintFloor {
  FrameResult watched;
  Pose2 true_motion;
};

DroppedOnAFaintFloor runDroppedOnAFaintFloor(bool motion_by_spectra, std::uint64_t seed, double contrast, int first_dropped, int dropped,
                                             int spin_every) {
  sim::SimulationSettings s = faintFloorOutdoors(sim::PathKind::loop, first_dropped + dropped + 4, seed);
  s.motion.spin_every = spin_every;
  const sim::SequenceSimulator simulator(s, faintTexture(512, contrast, seed));
  Config config = odometryOnlyConfig(s);
  config.fallback.motion_by_spectra = motion_by_spectra;
  Slam slam(config, nullptr);
  DroppedOnAFaintFloor run;
  int kept = 0;
  for (int i = 0; i < simulator.frameCount(); ++i) {
    if (i >= first_dropped && i < first_dropped + dropped) continue;
    const FrameResult r = slam.process(simulator.renderFrame(i), kept++);
    if (i == first_dropped + dropped) {
      run.watched = r;
      run.true_motion = between(simulator.groundTruth()[size_t(first_dropped - 1)], simulator.groundTruth()[size_t(i)]);
    }
  }
  return run;
}

}  // namespace

TEST(ImageAlignment, OnAFaintFloorAFrameLostAtFramesDroppedTakesTheMotionItsSpectraRegister) {
  // Odometry alone over the faint floor outdoors; 3 or 4 frames dropped without a trace (35-50 mm on, turning 40-50
  // degrees). Neither the features nor the images aligned from the robot's steps measure the frame after the drop:
  // its motion is not known (`fallback`). The images' spectra register it, as a bridge would (a clear phase correlation
  // peak at a shift of the ground): that motion is assumed, where before it was one usual step, turned as the spectra
  // alone told (or, on seed 4, where they did not, by the previous turn). Measured with / without: 4.6, 3.2 and 3.9 mm
  // and 0.01, 0.32 and 0.49 degrees / 40, 31 and 37 mm (seed 4 also 31 degrees) from the truth.
  struct Case {
    std::uint64_t seed;
    int dropped, spin_every;
  };
  for (const Case c : {Case{3u, 4, 0}, Case{4u, 3, 0}, Case{6u, 4, 30}}) {
    const DroppedOnAFaintFloor with = runDroppedOnAFaintFloor(true, c.seed, 3.0, 30, c.dropped, c.spin_every);
    EXPECT_EQ(with.watched.status, FrameStatus::fallback) << c.seed << " " << with.watched.statusName();
    EXPECT_GT(with.true_motion.translation().norm(), 0.03) << c.seed;
    EXPECT_LT((with.watched.odometry.translation() - with.true_motion.translation()).norm(), 0.006) << c.seed;
    EXPECT_LT(std::abs(wrapAngle(with.watched.odometry.theta - with.true_motion.theta)), 0.6 * kDeg) << c.seed;
  }
  // Without, on seed 4 alone (to keep the test's time down): one usual step, by the previous turn.
  const DroppedOnAFaintFloor without = runDroppedOnAFaintFloor(false, 4u, 3.0, 30, 3, 0);
  EXPECT_EQ(without.watched.status, FrameStatus::fallback) << without.watched.statusName();
  EXPECT_GT((without.watched.odometry.translation() - without.true_motion.translation()).norm(), 0.025);
  EXPECT_GT(std::abs(wrapAngle(without.watched.odometry.theta - without.true_motion.theta)), 20.0 * kDeg);
}
