#include "groundslam/core/ImageAlignment.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "groundslam/core/ImageReduction.hpp"

namespace groundslam {
namespace {

cv::Matx33d homogeneous(const cv::Matx23d& W) { return {W(0, 0), W(0, 1), W(0, 2), W(1, 0), W(1, 1), W(1, 2), 0.0, 0.0, 1.0}; }

cv::Matx23d affinePart(const cv::Matx33d& H) { return {H(0, 0), H(0, 1), H(0, 2), H(1, 0), H(1, 1), H(1, 2)}; }

/// How far two warps take the image's centre and corners apart (pixels of the image of size `size`).
double warpDistance(const cv::Matx23d& a, const cv::Matx23d& b, cv::Size size) {
  const double w = size.width - 1.0, h = size.height - 1.0;
  const std::array<cv::Vec3d, 5> probes{cv::Vec3d(0, 0, 1), cv::Vec3d(w, 0, 1), cv::Vec3d(0, h, 1), cv::Vec3d(w, h, 1),
                                        cv::Vec3d(w / 2, h / 2, 1)};
  double farthest = 0.0;
  for (const cv::Vec3d& p : probes) farthest = std::max(farthest, cv::norm((a - b) * p));
  return farthest;
}

/// One ECC run from `start` (reduced pixels); empty when it does not converge.
std::optional<std::pair<cv::Matx23d, double>> eccFrom(const cv::Mat& previous, const cv::Mat& current, const cv::Mat& mask,
                                                      const cv::Matx23d& start, int max_iterations) {
  cv::Mat warp;
  cv::Mat(start).convertTo(warp, CV_32F);
  try {
    // Template: the current image; input: the previous one. The warp maps a current pixel to the previous image.
    const double correlation = cv::findTransformECC(current, previous, warp, cv::MOTION_EUCLIDEAN,
                                                    cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, max_iterations, 1e-4),
                                                    mask, 5);
    if (!std::isfinite(correlation)) return std::nullopt;
    cv::Matx23d W;
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < 3; ++c) W(r, c) = static_cast<double>(warp.at<float>(r, c));
    }
    return std::make_pair(W, correlation);
  } catch (const cv::Exception&) {
    return std::nullopt;  // OpenCV reports a diverging or uncorrelated alignment by throwing: here it is data
  }
}

/// The bar's tests of the correlations alone (all but the probes' spread).
bool clearsBarByCorrelation(const ImageAlignment& aligned, const AlignmentBar& bar) {
  const double rival = std::max(aligned.rest_correlation, aligned.rival_correlation);
  return aligned.converged && aligned.correlation >= bar.min_correlation && 1.0 - rival >= bar.rest_ratio * (1.0 - aligned.correlation);
}

/// ECC's correlation coefficient of two images over a mask: zero-mean, normalised (-1 when either is flat there
/// or the mask holds fewer than `min_pixels`).
double maskedCorrelation(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask, double min_pixels) {
  cv::Scalar mean_a, std_a, mean_b, std_b;
  cv::meanStdDev(a, mean_a, std_a, mask);
  cv::meanStdDev(b, mean_b, std_b, mask);
  const double n = cv::countNonZero(mask);
  if (n <= min_pixels || !(std_a[0] > 0.0) || !(std_b[0] > 0.0)) return -1.0;
  cv::Mat product = (a - mean_a[0]).mul(b - mean_b[0]);
  return cv::sum(product.setTo(0.0, mask == 0))[0] / (n * std_a[0] * std_b[0]);
}

}  // namespace

cv::Matx23d toReducedPixels(const cv::Matx23d& W, double scale) {
  const cv::Matx33d S = reducedToOriginal(scale);
  return affinePart(S.inv() * homogeneous(W) * S);
}

cv::Matx23d toOriginalPixels(const cv::Matx23d& W_reduced, double scale) {
  const cv::Matx33d S = reducedToOriginal(scale);
  return affinePart(S * homogeneous(W_reduced) * S.inv());
}

AlignmentImage alignmentImage(const cv::Mat& gray, const ImageAlignmentSettings& settings, int reduced_by) {
  AlignmentImage aligned;
  const ReducedImage reduced = reduceByWholeFactor(gray, settings.width_px);
  const double blur_px = std::max(1.0, settings.highpass_fraction * reduced.pixels.cols);
  cv::Mat background;
  cv::GaussianBlur(reduced.pixels, background, cv::Size(0, 0), blur_px, 0.0, cv::BORDER_REFLECT);
  aligned.pixels = reduced.pixels - background;
  if (settings.normalise_contrast) {
    // Divided by the local contrast (a floor of two grey levels' contrast and sensor noise is not lifted above it),
    // scaled to stay in grey levels of a well-lit floor (the still test's texture threshold is in those).
    constexpr double kMinContrast = 2.0, kGreyLevels = 20.0;
    cv::Mat contrast;
    cv::GaussianBlur(aligned.pixels.mul(aligned.pixels), contrast, cv::Size(0, 0), blur_px, 0.0, cv::BORDER_REFLECT);
    cv::sqrt(contrast + kMinContrast * kMinContrast, contrast);
    aligned.pixels = kGreyLevels * aligned.pixels / contrast;
    if (settings.light_edge_slope > 0.0) {
      // Where the light itself changes steeply (the edge of the robot's shadow, a glare's rim) the high-pass leaves
      // a line that moves as the light does, not as the ground: those pixels are set to 0, no texture. The slope is
      // the background's change over one blur width, as a share of its level (a floor of 5 grey levels).
      cv::Mat dx, dy, slope;
      cv::Sobel(background, dx, CV_32F, 1, 0, 3, 1.0 / 8.0);
      cv::Sobel(background, dy, CV_32F, 0, 1, 3, 1.0 / 8.0);
      cv::magnitude(dx, dy, slope);
      slope = slope * blur_px / (background + 5.0);
      aligned.ground = slope <= settings.light_edge_slope;
      aligned.pixels.setTo(0.0f, slope > settings.light_edge_slope);
    }
  }
  aligned.scale = static_cast<double>(reduced.factor) * std::max(1, reduced_by);
  return aligned;
}

namespace {

/// Local normalised cross-correlation of two images, pixel by pixel, over 7 x 7 neighbourhoods; and where both
/// neighbourhoods have texture (a few grey levels of contrast: flat ones look alike anywhere).
std::pair<cv::Mat, cv::Mat> localCorrelation(const cv::Mat& a, const cv::Mat& b) {
  const cv::Size window(7, 7);
  cv::Mat mean_a, mean_b, aa, bb, ab;
  cv::blur(a, mean_a, window);
  cv::blur(b, mean_b, window);
  cv::blur(a.mul(a), aa, window);
  cv::blur(b.mul(b), bb, window);
  cv::blur(a.mul(b), ab, window);
  const cv::Mat var_a = aa - mean_a.mul(mean_a), var_b = bb - mean_b.mul(mean_b), cov = ab - mean_a.mul(mean_b);
  cv::Mat denominator;
  cv::sqrt(cv::max(var_a.mul(var_b), 1e-6), denominator);
  constexpr double kMinVariance = 4.0;
  return {cov / denominator, (var_a > kMinVariance) & (var_b > kMinVariance)};
}

}  // namespace

cv::Mat movingPixels(const cv::Mat& previous, const cv::Mat& current, const cv::Matx23d& W_expected, double still_correlation) {
  cv::Mat moved_previous;
  cv::warpAffine(previous, moved_previous, W_expected, previous.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REFLECT);
  return movingPixels(previous, moved_previous, current, still_correlation);
}

cv::Mat movingPixels(const cv::Mat& previous, const cv::Mat& moved_previous, const cv::Mat& current, double still_correlation) {
  // Still: alike in place, and more alike in place than where the expected motion puts the ground (a smooth
  // floor's gradients look alike after any small shift; a shadow's edge only in place).
  const auto [in_place, textured] = localCorrelation(previous, current);
  const cv::Mat moved = localCorrelation(moved_previous, current).first;
  cv::Mat still = (in_place > still_correlation) & (in_place > moved) & textured;
  cv::dilate(still, still, cv::Mat::ones(5, 5, CV_8U));
  cv::Mat moving;
  cv::bitwise_not(still, moving);
  return moving;
}

namespace {

/// The two images with what stayed still blanked (and the mask of the rest): neither side's artifacts can pull the
/// warp to rest.
struct GroundPixels {
  cv::Mat previous, current, moving;
};

GroundPixels groundPixels(const AlignmentImage& previous, const AlignmentImage& current, const cv::Matx23d& expected,
                          const ImageAlignmentSettings& settings) {
  GroundPixels ground;
  ground.moving = movingPixels(previous.pixels, current.pixels, toReducedPixels(expected, previous.scale), settings.still_correlation);
  for (const cv::Mat& light : {previous.ground, current.ground}) {
    if (!light.empty()) cv::bitwise_and(ground.moving, light, ground.moving);
  }
  ground.previous = cv::Mat::zeros(previous.pixels.size(), CV_32F);
  ground.current = ground.previous.clone();
  previous.pixels.copyTo(ground.previous, ground.moving);
  current.pixels.copyTo(ground.current, ground.moving);
  return ground;
}

bool alignable(const AlignmentImage& previous, const AlignmentImage& current) {
  return !previous.pixels.empty() && previous.pixels.size() == current.pixels.size() && previous.scale == current.scale;
}

}  // namespace

ImageAlignment refineAlignment(const AlignmentImage& previous, const AlignmentImage& current, const cv::Matx23d& start,
                               const ImageAlignmentSettings& settings) {
  ImageAlignment refined;
  if (!alignable(previous, current)) return refined;
  GroundPixels ground = groundPixels(previous, current, start, settings);
  // ECC masks only the previous image (its input); the current image's blanked pixels would still count, a pattern
  // fixed in the image whose overlap with the previous one's is best at rest (measured on the outdoor carpet: turns
  // 0.2-0.5% short). The previous pixels that the start puts on them are left out too.
  const cv::Matx23d start_reduced = toReducedPixels(start, previous.scale);
  cv::Mat blanked_current_seen;
  cv::warpAffine(ground.moving, blanked_current_seen, start_reduced, ground.moving.size(), cv::INTER_NEAREST, cv::BORDER_CONSTANT, 255);
  cv::bitwise_and(ground.moving, blanked_current_seen, ground.moving);
  const int margin = static_cast<int>(settings.refine_border_fraction * ground.moving.cols);
  if (2 * margin >= std::min(ground.moving.cols, ground.moving.rows)) return refined;
  cv::Mat inside = cv::Mat::zeros(ground.moving.size(), CV_8U);
  inside(cv::Rect(margin, margin, ground.moving.cols - 2 * margin, ground.moving.rows - 2 * margin)).setTo(255);
  cv::bitwise_and(ground.moving, inside, ground.moving);
  const auto solution = eccFrom(ground.previous, ground.current, ground.moving, start_reduced, settings.max_iterations);
  if (!solution) return refined;
  refined.converged = true;
  refined.correlation = solution->second;
  refined.W_previous_current = toOriginalPixels(solution->first, previous.scale);
  return refined;
}

bool clearsBar(const ImageAlignment& aligned, const AlignmentBar& bar) {
  return clearsBarByCorrelation(aligned, bar) && aligned.spread_px * bar.metres_per_px <= bar.max_spread_m;
}

ImageAlignment alignImages(const AlignmentImage& previous, const AlignmentImage& current, const std::vector<cv::Matx23d>& starts,
                           const ImageAlignmentSettings& settings, const AlignmentBar& bar) {
  ImageAlignment best;
  if (!alignable(previous, current) || starts.empty()) return best;
  const GroundPixels ground = groundPixels(previous, current, starts.front(), settings);
  const cv::Mat& previous_ground = ground.previous;
  const cv::Mat& current_ground = ground.current;
  const cv::Mat& moving = ground.moving;

  // The starts are aligned side by side (each run is independent; OpenCV's threads), then taken in their order.
  std::vector<std::optional<std::pair<cv::Matx23d, double>>> ended(starts.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(starts.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      const size_t k = static_cast<size_t>(i);
      ended[k] = eccFrom(previous_ground, current_ground, moving, toReducedPixels(starts[k], previous.scale), settings.max_iterations);
    }
  });
  std::vector<std::pair<cv::Matx23d, double>> solutions;
  for (const auto& solution : ended) {
    if (solution) solutions.push_back(*solution);
  }
  if (solutions.empty()) return best;
  const auto winner = std::max_element(solutions.begin(), solutions.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  const cv::Matx23d best_reduced = winner->first;
  best.correlation = winner->second;
  best.converged = true;
  for (const auto& [warp, correlation] : solutions) {
    if (warpDistance(warp, best_reduced, previous.pixels.size()) > settings.probe_px) {
      best.rival_correlation = std::max(best.rival_correlation, correlation);
    }
  }
  // ECC's correlation at rest, over the pixels the alignment used.
  best.rest_correlation = maskedCorrelation(previous_ground, current_ground, moving, 0.0);
  best.W_previous_current = toOriginalPixels(best_reduced, previous.scale);
  if (!clearsBarByCorrelation(best, bar)) {
    best.spread_px = std::numeric_limits<double>::infinity();  // not probed: it cannot be believed whatever they show
    return best;
  }
  // Probes: from starts shifted around the solution, the alignment must come back to it.
  const double d = settings.probe_px;
  for (const cv::Vec2d& shift : {cv::Vec2d(d, 0), cv::Vec2d(0, d), cv::Vec2d(-d, 0), cv::Vec2d(0, -d)}) {
    cv::Matx23d start = best_reduced;
    start(0, 2) += shift[0];
    start(1, 2) += shift[1];
    const auto probe = eccFrom(previous_ground, current_ground, moving, start, settings.max_iterations);
    const double off = probe ? warpDistance(probe->first, best_reduced, previous.pixels.size()) : d * 1e3;
    best.spread_px = std::max(best.spread_px, off * previous.scale);
    if (best.spread_px * bar.metres_per_px > bar.max_spread_m) break;  // already beyond the bar: the rest cannot help
  }
  return best;
}

std::vector<cv::Matx23d> turnCandidates(const AlignmentImage& previous, const AlignmentImage& current, const cv::Point2d& centre_px,
                                        double step_deg, double margin) {
  if (previous.pixels.empty() || previous.pixels.size() != current.pixels.size() || !(step_deg > 0.0)) return {};
  constexpr int kCoarse = 4;
  cv::Mat p, c;
  const cv::Size small(std::max(1, previous.pixels.cols / kCoarse), std::max(1, previous.pixels.rows / kCoarse));
  cv::resize(previous.pixels, p, small, 0.0, 0.0, cv::INTER_AREA);
  cv::resize(current.pixels, c, small, 0.0, 0.0, cv::INTER_AREA);
  const double scale = previous.scale * kCoarse;
  const cv::Point2d centre((centre_px.x - (scale - 1.0) / 2.0) / scale, (centre_px.y - (scale - 1.0) / 2.0) / scale);
  const cv::Mat ones = cv::Mat::ones(small, CV_8U);
  std::vector<std::pair<double, cv::Matx23d>> turns;  // correlation, warp in coarse pixels
  const int count = static_cast<int>(std::lround(360.0 / step_deg));
  for (int i = 0; i < count; ++i) {
    const double angle = (i * step_deg - 180.0) * M_PI / 180.0;
    const double co = std::cos(angle), si = std::sin(angle);
    const cv::Matx23d W(co, -si, centre.x - co * centre.x + si * centre.y, si, co, centre.y - si * centre.x - co * centre.y);
    cv::Mat turned, inside;
    cv::warpAffine(p, turned, W, small, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP);
    cv::warpAffine(ones, inside, W, small, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP);
    cv::Mat shown;
    cv::erode(inside, shown, cv::Mat::ones(3, 3, CV_8U));  // no interpolated border
    turns.emplace_back(maskedCorrelation(turned, c, shown, 0.25 * small.area()), W);
  }
  double best = -1.0;
  for (const auto& turn : turns) best = std::max(best, turn.first);
  std::vector<std::pair<double, cv::Matx23d>> kept;
  for (size_t i = 0; i < turns.size(); ++i) {
    const double before = turns[(i + turns.size() - 1) % turns.size()].first, after = turns[(i + 1) % turns.size()].first;
    const bool local_best = turns[i].first >= before && turns[i].first >= after;
    if (local_best && turns[i].first >= best - margin && turns[i].first > 0.0) kept.push_back(turns[i]);
  }
  std::sort(kept.begin(), kept.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<cv::Matx23d> warps;
  for (const auto& turn : kept) warps.push_back(toOriginalPixels(turn.second, scale));
  return warps;
}

}  // namespace groundslam
