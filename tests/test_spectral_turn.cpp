// The turn between two images from the magnitudes of their spectra (core/SpectralTurn.hpp): known turns recovered
// whatever the translation, up to half a turn; nothing claimed between unrelated images.
#include <cmath>
#include <cstdint>
#include <utility>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "groundslam/core/SpectralTurn.hpp"

using namespace groundslam;

namespace {

constexpr double kDeg = M_PI / 180.0;

/// Seeded noise blurred to grains about `blur_px` wide: a floor with texture at every angle.
cv::Mat grainyFloor(int size, double blur_px, std::uint64_t seed) {
  cv::Mat noise(size, size, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(), blur_px);
  // Elongated grains as on asphalt or carpet: the spectrum's magnitude has a direction to turn.
  cv::Mat streaks;
  cv::GaussianBlur(noise, streaks, cv::Size(), 4.0 * blur_px, blur_px);
  return noise + 2.0f * streaks;
}

/// The 240 x 320 view of `floor` centred `offset` pixels from its centre, its content turned counterclockwise (as
/// displayed) by `turn_deg` about the view's centre.
cv::Mat view(const cv::Mat& floor, cv::Point2f offset, double turn_deg) {
  const cv::Point2f centre(0.5f * static_cast<float>(floor.cols) + offset.x, 0.5f * static_cast<float>(floor.rows) + offset.y);
  cv::Mat M = cv::getRotationMatrix2D(centre, turn_deg, 1.0);
  M.at<double>(0, 2) -= centre.x - 160.0;
  M.at<double>(1, 2) -= centre.y - 120.0;
  cv::Mat out;
  cv::warpAffine(floor, out, M, cv::Size(320, 240), cv::INTER_LINEAR);
  return out;
}

double halfTurnApart(double a, double b) {
  const double d = std::remainder(a - b, M_PI);
  return std::abs(d);
}

}  // namespace

TEST(SpectralTurn, KnownTurnsAreRecoveredWhereverTheViewMoved) {
  const cv::Mat floor = grainyFloor(900, 1.5, 7);
  const cv::Mat previous = view(floor, {0, 0}, 0.0);
  for (const double turn_deg : {-75.0, -30.0, -8.0, 0.0, 3.0, 14.0, 45.0, 88.0}) {
    // Moved by a third of the view as well: the magnitudes do not see the translation.
    const cv::Mat current = view(floor, {60.0f, -40.0f}, turn_deg);
    const SpectralTurn found = spectralTurn(previous, current);
    EXPECT_LT(halfTurnApart(found.turn_rad, turn_deg * kDeg), 0.75 * kDeg) << turn_deg << " found " << found.turn_rad / kDeg;
    EXPECT_GT(found.peak_ratio, 1.5) << turn_deg;
  }
}

TEST(SpectralTurn, HalfATurnIsNotTold) {
  const cv::Mat floor = grainyFloor(900, 1.5, 8);
  const SpectralTurn found = spectralTurn(view(floor, {0, 0}, 0.0), view(floor, {20.0f, 10.0f}, 180.0 + 20.0));
  EXPECT_LT(halfTurnApart(found.turn_rad, 20.0 * kDeg), 0.75 * kDeg);  // 20 or 200 degrees: the same spectrum
}

TEST(SpectralTurn, UnrelatedFloorsGiveNoClearTurn) {
  // Two different floors of the same kind: whatever turn is best, it is not much better than the others.
  const SpectralTurn found = spectralTurn(view(grainyFloor(900, 1.5, 9), {0, 0}, 0.0), view(grainyFloor(900, 1.5, 10), {0, 0}, 30.0));
  EXPECT_LT(found.peak_ratio, 1.3);
  const SpectralTurn same = spectralTurn(view(grainyFloor(900, 1.5, 9), {0, 0}, 0.0), view(grainyFloor(900, 1.5, 9), {30, 0}, 30.0));
  EXPECT_GT(same.peak_ratio, 2.0 * found.peak_ratio);
}

TEST(SpectralTurn, UnusableInputIsAResultNotACrash) {
  EXPECT_EQ(spectralTurn(cv::Mat(), cv::Mat()).peak_ratio, 0.0);
  EXPECT_EQ(spectralTurn(cv::Mat::zeros(100, 100, CV_8U), cv::Mat::zeros(90, 100, CV_8U)).peak_ratio, 0.0);
  EXPECT_EQ(spectralTurn(cv::Mat::zeros(100, 100, CV_8U), cv::Mat::zeros(100, 100, CV_8U)).peak_ratio, 0.0);  // flat
  EXPECT_EQ(spectralTurn(cv::Mat::zeros(8, 8, CV_32F), cv::Mat::zeros(8, 8, CV_32F)).peak_ratio, 0.0);  // too small
}

TEST(SpectralTurn, ThePhaseCorrelationTellsTheRightHalfTurn) {
  // Turned by 120 degrees and moved: the spectra say -60 or 120. Turned back by 120, the view matches the first by a
  // translation; turned back by -60, it does not.
  const cv::Mat floor = grainyFloor(900, 1.5, 11);
  const cv::Mat previous = view(floor, {0, 0}, 0.0), current = view(floor, {25.0f, -15.0f}, 120.0);
  const SpectralTurn found = spectralTurn(previous, current);
  ASSERT_LT(halfTurnApart(found.turn_rad, 120.0 * kDeg), 0.75 * kDeg);
  const double right = phasePeakAfterTurn(previous, current, 120.0 * kDeg);
  const double opposite = phasePeakAfterTurn(previous, current, -60.0 * kDeg);
  EXPECT_GT(right, 4.0 * opposite) << right << " " << opposite;
  EXPECT_GT(right, 0.2);
  EXPECT_EQ(phasePeakAfterTurn(cv::Mat(), cv::Mat(), 0.0), 0.0);
}

namespace {

/// Where the ground seen at `current_px` in view(floor, offset, turn_deg) is seen in view(floor, {0, 0}, 0).
cv::Point2d seenBefore(const cv::Mat& floor, cv::Point2f offset, double turn_deg, cv::Point2d current_px) {
  const cv::Point2d centre(0.5 * floor.cols + offset.x, 0.5 * floor.rows + offset.y);
  // view(): pixel = R(turn) (ground - centre) + (160, 120), R counterclockwise as displayed (y down).
  const double c = std::cos(turn_deg * kDeg), s = std::sin(turn_deg * kDeg);
  const cv::Point2d d = current_px - cv::Point2d(160.0, 120.0);
  const cv::Point2d ground = centre + cv::Point2d(c * d.x - s * d.y, s * d.x + c * d.y);
  return ground - cv::Point2d(0.5 * floor.cols, 0.5 * floor.rows) + cv::Point2d(160.0, 120.0);
}

}  // namespace

TEST(SpectralTurn, WithTheTurnKnownThePhaseCorrelationGivesTheShift) {
  const cv::Mat floor = grainyFloor(900, 1.5, 12);
  const cv::Mat previous = view(floor, {0, 0}, 0.0);
  for (const double turn_deg : {-90.0, -17.0, 0.0, 76.0}) {
    const cv::Point2f offset(18.0f, -41.0f);
    const cv::Mat current = view(floor, offset, turn_deg);
    const TurnAndShift found = shiftAfterTurn(previous, current, turn_deg * kDeg);
    EXPECT_GT(found.response, 0.2) << turn_deg;
    // Every corner of the view and its centre land where the ground they show was seen: the turn is exact here,
    // so within the phase correlation's fraction of a pixel.
    for (const cv::Point2d p : {cv::Point2d(160, 120), cv::Point2d(0, 0), cv::Point2d(319, 0), cv::Point2d(0, 239), cv::Point2d(319, 239)}) {
      const cv::Vec2d mapped = found.W_previous_current * cv::Vec3d(p.x, p.y, 1.0);
      const cv::Point2d expected = seenBefore(floor, offset, turn_deg, p);
      EXPECT_LT(std::hypot(mapped[0] - expected.x, mapped[1] - expected.y), 0.5) << turn_deg << " at " << p;
    }
  }
  EXPECT_EQ(shiftAfterTurn(cv::Mat(), cv::Mat(), 0.0).response, 0.0);
}

TEST(SpectralTurn, AShiftPastHalfTheImageIsNotTakenForItsAliasTheOtherWay) {
  // Frames dropped: the views overlap by 35-45% of the central square, whose phase correlation knows a shift only
  // modulo its side (a 150-pixel shift down reads as 90 up). The overlap's correlation tells the two apart.
  const cv::Mat floor = grainyFloor(900, 1.5, 17);
  const cv::Mat previous = view(floor, {0, 0}, 0.0);
  for (const auto& [offset, turn_deg] : {std::pair{cv::Point2f(0.0f, 150.0f), 0.0}, std::pair{cv::Point2f(-135.0f, 20.0f), 0.0},
                                        std::pair{cv::Point2f(25.0f, -140.0f), 30.0}}) {
    const cv::Mat current = view(floor, offset, turn_deg);
    const TurnAndShift found = shiftAfterTurn(previous, current, turn_deg * kDeg);
    for (const cv::Point2d p : {cv::Point2d(160, 120), cv::Point2d(0, 0), cv::Point2d(319, 239)}) {
      const cv::Vec2d mapped = found.W_previous_current * cv::Vec3d(p.x, p.y, 1.0);
      const cv::Point2d expected = seenBefore(floor, offset, turn_deg, p);
      EXPECT_LT(std::hypot(mapped[0] - expected.x, mapped[1] - expected.y), 1.5) << offset << " at " << p;
    }
  }
}

TEST(SpectralTurn, AShadowThatMovedInTheImageDoesNotChooseTheAlias) {
  // The robot's shadow turns with its heading: after a sharp turn it darkens another corner of the image. Shifted
  // 80-105 pixels of the central square's 240, the views overlap by 135-160 rows; the alias the other way overlaps by
  // 80-105 rows, and there the two shadows' corners lie at one place: in brightness that overlap correlates better (the shadows are about six
  // times the grain's spread deep; measured, the alias wins without the grain filter), while only the true shift
  // lines up the ground's grain.
  const cv::Mat floor = grainyFloor(900, 1.5, 23);
  cv::Mat shadow_top(240, 320, CV_32F, cv::Scalar(0.0f)), shadow_bottom(240, 320, CV_32F, cv::Scalar(0.0f));
  shadow_top(cv::Rect(0, 0, 160, 110)).setTo(cv::Scalar(-2.0));
  shadow_bottom(cv::Rect(0, 130, 160, 110)).setTo(cv::Scalar(-2.0));
  cv::GaussianBlur(shadow_top, shadow_top, cv::Size(), 6.0);
  cv::GaussianBlur(shadow_bottom, shadow_bottom, cv::Size(), 6.0);
  const cv::Mat previous = view(floor, {0, 0}, 0.0) + shadow_bottom;
  for (const float down : {80.0f, 95.0f, 105.0f}) {
    const cv::Point2f offset(0.0f, -down);
    const cv::Mat current = view(floor, offset, 0.0) + shadow_top;
    const TurnAndShift found = shiftAfterTurn(previous, current, 0.0);
    const cv::Vec2d mapped = found.W_previous_current * cv::Vec3d(160.0, 120.0, 1.0);
    const cv::Point2d expected = seenBefore(floor, offset, 0.0, {160.0, 120.0});
    EXPECT_LT(std::hypot(mapped[0] - expected.x, mapped[1] - expected.y), 1.5) << down;
  }
}
