// The previous frame's side of the mount estimate's pairs, tracked by the images (core/PointTracking.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "groundslam/core/PointTracking.hpp"

namespace groundslam {
namespace {

constexpr double kDeg = M_PI / 180.0;

/// A blurred noise floor, larger than the images cut from it.
cv::Mat floorTexture() {
  cv::Mat texture(400, 480, CV_32F);
  cv::RNG rng(7);
  rng.fill(texture, cv::RNG::NORMAL, 128.0, 100.0);  // about 20 grey levels of contrast once blurred
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 1.5);
  return texture;
}

/// The warp of current pixels to previous ones a camera 439 px in focal length makes when it turns by `turn_deg`
/// about its axis, tilts by `tilt_deg` about its x axis and shifts by (dx, dy) pixels.
cv::Matx33d cameraWarp(double turn_deg, double tilt_deg, double dx, double dy) {
  const cv::Matx33d K(439.0, 0.0, 160.0, 0.0, 439.0, 120.0, 0.0, 0.0, 1.0);
  const double c = std::cos(turn_deg * kDeg), s = std::sin(turn_deg * kDeg);
  const double ct = std::cos(tilt_deg * kDeg), st = std::sin(tilt_deg * kDeg);
  const cv::Matx33d turn(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0), tilt(1.0, 0.0, 0.0, 0.0, ct, -st, 0.0, st, ct);
  const cv::Matx33d shift(1.0, 0.0, dx, 0.0, 1.0, dy, 0.0, 0.0, 1.0);
  return shift * K * turn * tilt * K.inv();
}

/// The current image (cut from the texture at an offset) and the previous one, in which current pixel p is seen at
/// H_previous_current p; 8-bit, with noise of 2 grey levels in each.
std::pair<cv::Mat, cv::Mat> imagePair(const cv::Matx33d& H_previous_current) {
  const cv::Mat texture = floorTexture();
  const cv::Matx33d offset(1.0, 0.0, 80.0, 0.0, 1.0, 80.0, 0.0, 0.0, 1.0);
  cv::Mat current, previous;
  cv::warpPerspective(texture, current, offset, cv::Size(320, 240), cv::INTER_CUBIC | cv::WARP_INVERSE_MAP);
  cv::warpPerspective(texture, previous, offset * H_previous_current.inv(), cv::Size(320, 240), cv::INTER_CUBIC | cv::WARP_INVERSE_MAP);
  cv::RNG rng(11);
  for (cv::Mat* image : {&current, &previous}) {
    cv::Mat noise(image->size(), CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 2.0);
    *image += noise;
    image->convertTo(*image, CV_8U);
  }
  return {previous, current};
}

std::vector<cv::Point2d> grid() {
  std::vector<cv::Point2d> points;
  for (int y = 30; y <= 210; y += 12) {
    for (int x = 30; x <= 290; x += 12) points.emplace_back(x + 0.37, y + 0.61);
  }
  return points;
}

cv::Point2d warped(const cv::Matx33d& H, const cv::Point2d& p) {
  const cv::Vec3d q = H * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

}  // namespace

TEST(PointTracking, AOneDegreeTiltIsFoundToAFewHundredthsOfAPixel) {
  // A 12-degree turn, a 1-degree tilt (1 px of perspective at the corners) and a 17-pixel step; the tracker starts
  // from the warp without its perspective, shifted by 0.7 px (a fit of matched keypoints). Measured: median error
  // 0.038 px, 95th percentile 0.081 px; 275 of 352 points tracked (the others left the 2-pixel leash, the plane's
  // 0.3-pixel agreement or a window near the image's border), every start at least 0.8 px off.
  const cv::Matx33d truth = cameraWarp(12.0, 1.0, 17.0, -4.0);
  const auto [previous, current] = imagePair(truth);
  const PointTrackingSettings settings;
  cv::Matx33d start = truth * (1.0 / truth(2, 2));
  start(2, 0) = start(2, 1) = 0.0;
  start(0, 2) += 0.6;
  start(1, 2) -= 0.4;
  const std::vector<cv::Point2d> points = grid();
  const auto tracked = trackPoints(trackingImage(previous, settings), trackingImage(current, settings), points, start, settings);
  std::vector<double> errors, start_errors;
  for (size_t i = 0; i < points.size(); ++i) {
    start_errors.push_back(cv::norm(warped(start, points[i]) - warped(truth, points[i])));
    if (tracked[i]) errors.push_back(cv::norm(*tracked[i] - warped(truth, points[i])));
  }
  std::sort(start_errors.begin(), start_errors.end());
  ASSERT_GE(static_cast<double>(errors.size()), 0.75 * static_cast<double>(points.size()));
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.05);
  EXPECT_LT(errors[errors.size() * 95 / 100], 0.1);
  EXPECT_GT(start_errors.front(), 0.5);  // the start alone is far off
}

TEST(PointTracking, WhatStaysStillInTheImageIsLeftOut) {
  // A dark blotch on the lens: in the same place in both images while the floor moves 17 px. Points on its edge
  // would track the blotch; they slide off the expected warp or disagree with the floor's plane and are left out,
  // while the floor's points still track to a few hundredths of a pixel.
  const cv::Matx33d truth = cameraWarp(5.0, 0.5, 17.0, 3.0);
  auto [previous, current] = imagePair(truth);
  for (cv::Mat* image : {&previous, &current}) cv::circle(*image, cv::Point(160, 120), 30, cv::Scalar(10), cv::FILLED, cv::LINE_AA);
  const PointTrackingSettings settings;
  const std::vector<cv::Point2d> points = grid();
  const auto tracked = trackPoints(trackingImage(previous, settings), trackingImage(current, settings), points, truth, settings);
  int on_edge = 0, on_edge_tracked = 0, floor = 0, floor_tracked = 0;
  double worst = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    const double r = cv::norm(points[i] - cv::Point2d(160.0, 120.0));
    if (std::abs(r - 30.0) < 5.0) {
      ++on_edge;
      on_edge_tracked += tracked[i] ? 1 : 0;
    } else if (r > 45.0) {
      ++floor;
      if (tracked[i]) {
        ++floor_tracked;
        worst = std::max(worst, cv::norm(*tracked[i] - warped(truth, points[i])));
      }
    }
  }
  ASSERT_GT(on_edge, 10);
  EXPECT_EQ(on_edge_tracked, 0);
  EXPECT_GE(floor_tracked, 0.75 * floor);
  EXPECT_LT(worst, 0.4);  // measured: 0.10 px; 288 of 307 floor points tracked, none of the 14 on the edge
  // The still-parts mask alone (the other checks opened wide but the 2-pixel leash) leaves out the points on the
  // blotch's edge; without it 6 of the 14 are kept.
  PointTrackingSettings open;
  open.max_round_trip_px = open.max_error_px = 100.0;
  open.max_mismatch_ratio = 1e9;
  const auto onEdgeTracked = [&](const PointTrackingSettings& s) {
    const auto t = trackPoints(trackingImage(previous, s), trackingImage(current, s), points, truth, s);
    int n = 0;
    for (size_t i = 0; i < points.size(); ++i) n += t[i] && std::abs(cv::norm(points[i] - cv::Point2d(160.0, 120.0)) - 30.0) < 5.0 ? 1 : 0;
    return n;
  };
  EXPECT_EQ(onEdgeTracked(open), 0);
  open.still_correlation = 0.0;
  EXPECT_GT(onEdgeTracked(open), 0);
}

namespace {

/// Errors (pixels, sorted) of the tracked points among `points`, and how many were tracked.
std::vector<double> trackingErrors(const cv::Mat& previous, const cv::Mat& current, const std::vector<cv::Point2d>& points,
                                   const cv::Matx33d& truth, const PointTrackingSettings& settings) {
  const auto tracked = trackPoints(trackingImage(previous, settings), trackingImage(current, settings), points, truth, settings);
  std::vector<double> errors;
  for (size_t i = 0; i < points.size(); ++i) {
    if (tracked[i]) errors.push_back(cv::norm(*tracked[i] - warped(truth, points[i])));
  }
  std::sort(errors.begin(), errors.end());
  return errors;
}

/// Both images lit by `light` (a factor per pixel) and given `added` (grey levels per pixel): what the robot's
/// shadow and lamp do, at the same place in every image.
void relight(cv::Mat& image, const cv::Mat& light, const cv::Mat& added) {
  cv::Mat lit;
  image.convertTo(lit, CV_32F);
  lit = lit.mul(light) + added;
  lit.convertTo(image, CV_8U);
}

}  // namespace

TEST(PointTracking, UnderTheRobotsShadowAndGlareTheWindowsCompareTextureNotLight) {
  // The robot's shadow over the right of both images (soft edge) and its lamp's glare (a bright blob 32 px wide),
  // where they were while the floor moved 17 px and tilted by half a degree. The pre-warp moves the previous image
  // under them, so a window of raw grey levels also sees the light move; normalised, it compares texture.
  // Measured: median 0.030 px, 95th percentile 0.069 px, 289 of 352 tracked; without the normalisation 0.056 and
  // 0.22 px, 196 tracked.
  const cv::Matx33d truth = cameraWarp(5.0, 0.5, 17.0, 3.0);
  auto [previous, current] = imagePair(truth);
  cv::Mat shade(previous.size(), CV_32F, cv::Scalar(1.0)), glare(previous.size(), CV_32F);
  shade(cv::Rect(200, 0, previous.cols - 200, previous.rows)) = 0.35;
  cv::GaussianBlur(shade, shade, cv::Size(0, 0), 3.0);
  for (int row = 0; row < glare.rows; ++row) {
    for (int col = 0; col < glare.cols; ++col) {
      const double r2 = ((col - 110.0) * (col - 110.0) + (row - 110.0) * (row - 110.0)) / (32.0 * 32.0);
      glare.at<float>(row, col) = static_cast<float>(90.0 * std::exp(-0.5 * r2));
    }
  }
  for (cv::Mat* image : {&previous, &current}) relight(*image, shade, glare);
  PointTrackingSettings settings;
  const std::vector<double> normalised = trackingErrors(previous, current, grid(), truth, settings);
  settings.normalise_contrast = false;
  const std::vector<double> raw = trackingErrors(previous, current, grid(), truth, settings);
  ASSERT_GE(normalised.size(), 250u);
  EXPECT_LT(normalised[normalised.size() / 2], 0.05);
  EXPECT_LT(normalised[normalised.size() * 95 / 100], 0.1);
  ASSERT_FALSE(raw.empty());
  EXPECT_LT(raw.size(), normalised.size() - 50);
  EXPECT_GT(raw[raw.size() * 95 / 100], 0.15);
}

TEST(PointTracking, TooFewPointsGiveNone) {
  const cv::Matx33d truth = cameraWarp(0.0, 0.0, 5.0, 0.0);
  const auto [previous, current] = imagePair(truth);
  const PointTrackingSettings settings;
  const std::vector<cv::Point2d> points = grid();
  const std::vector<cv::Point2d> few(points.begin(), points.begin() + settings.min_points - 1);
  const auto tracked = trackPoints(trackingImage(previous, settings), trackingImage(current, settings), few, truth, settings);
  EXPECT_TRUE(std::none_of(tracked.begin(), tracked.end(), [](const auto& p) { return p.has_value(); }));
  // Images of different sizes: nothing, no exception.
  cv::Mat smaller;
  cv::resize(previous, smaller, cv::Size(160, 120));
  const auto mismatched = trackPoints(trackingImage(smaller, settings), trackingImage(current, settings), grid(), truth, settings);
  EXPECT_TRUE(std::none_of(mismatched.begin(), mismatched.end(), [](const auto& p) { return p.has_value(); }));
}

}  // namespace groundslam
