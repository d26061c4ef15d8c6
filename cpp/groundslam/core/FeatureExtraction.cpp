#include "groundslam/core/FeatureExtraction.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace groundslam {

OrbExtractor::OrbExtractor(const OrbSettings& s)
    : orb_(cv::ORB::create(s.num_features, static_cast<float>(s.scale_factor), s.num_levels, s.edge_threshold, 0, 2,
                           s.score_type == OrbScore::fast ? cv::ORB::FAST_SCORE : cv::ORB::HARRIS_SCORE, s.patch_size,
                           s.fast_threshold)),
      max_extraction_width_(s.max_extraction_width),
      subpixel_window_(s.subpixel_window),
      flatten_window_(s.flatten_window),
      flatten_min_range_(s.flatten_min_range) {}

int extractionReduction(int image_width, int max_extraction_width) {
  if (max_extraction_width <= 0 || image_width <= max_extraction_width) return 1;
  return (image_width + max_extraction_width - 1) / max_extraction_width;
}

int decoderReductionFor(int image_width, int max_extraction_width) {
  const int reduction = extractionReduction(image_width, max_extraction_width);
  for (int factor : {8, 4, 2}) {
    if (reduction % factor == 0) return factor;
  }
  return 1;
}

cv::Mat flattenIllumination(const cv::Mat& gray_image, double sigma_px, double min_range) {
  // The background light: a Gaussian blur computed on an image reduced to a few pixels per sigma (cheap at
  // any resolution), brought back to full size bilinearly: smooth, no ringing.
  // A whole reduction factor over a crop of whole blocks: OpenCV's fast path for area averaging.
  const int reduce = std::max(1, static_cast<int>(sigma_px / 4.0));
  const cv::Size reduced(std::max(1, gray_image.cols / reduce), std::max(1, gray_image.rows / reduce));  // never empty
  const cv::Mat whole_blocks = gray_image(cv::Rect(0, 0, std::min(gray_image.cols, reduced.width * reduce),
                                                   std::min(gray_image.rows, reduced.height * reduce)));
  cv::Mat small, background, flat;
  cv::resize(whole_blocks, small, reduced, 0.0, 0.0, cv::INTER_AREA);
  // Is there a patch of light much wider than any floor pattern (a lamp's glare)? Judged on a blur five
  // times wider, which leaves tiles, stains and grout lines out, computed on that image reduced five times more.
  cv::Mat tiny, wide;
  cv::resize(small, tiny, cv::Size(std::max(1, small.cols / 5), std::max(1, small.rows / 5)), 0.0, 0.0, cv::INTER_AREA);
  tiny.convertTo(tiny, CV_32F);
  cv::GaussianBlur(tiny, wide, cv::Size(0, 0), 5.0 * sigma_px / (reduce * 5.0), 0.0, cv::BORDER_REFLECT);
  double darkest = 0.0, brightest = 0.0;
  cv::minMaxLoc(wide, &darkest, &brightest);
  if (brightest - darkest < min_range) return gray_image;  // even light: the image is used as it is
  small.convertTo(small, CV_32F);
  cv::GaussianBlur(small, small, cv::Size(0, 0), sigma_px / reduce, 0.0, cv::BORDER_REFLECT);
  cv::resize(small, background, gray_image.size(), 0.0, 0.0, cv::INTER_LINEAR);
  // 128 + image - background, saturating: a smooth change of light becomes a constant grey.
  cv::Mat image;
  gray_image.convertTo(image, CV_32F);
  cv::Mat(image - background + 128.0f).convertTo(flat, CV_8U);
  return flat;
}

ImageFeatures OrbExtractor::detect(const cv::Mat& gray_image, int reduced_by) const {
  ImageFeatures features;
  reduced_by = std::max(1, reduced_by);
  int reduction = std::max(reduced_by, extractionReduction(gray_image.cols * reduced_by, max_extraction_width_));
  if (reduction % reduced_by != 0) reduction = reduced_by;  // a decoder's reduction that does not divide ours: keep it as is
  cv::Mat reduced = gray_image;
  if (reduction > reduced_by) {
    // Whole blocks only (the last partial row or column of blocks is left out): reduced pixel i then averages
    // exactly the pixels the mapping back below assumes, on both axes.
    const int rest = reduction / reduced_by;
    const cv::Size size(std::max(1, gray_image.cols / rest), std::max(1, gray_image.rows / rest));
    const cv::Mat whole_blocks = gray_image(cv::Rect(0, 0, std::min(gray_image.cols, size.width * rest),
                                                     std::min(gray_image.rows, size.height * rest)));
    cv::resize(whole_blocks, reduced, size, 0.0, 0.0, cv::INTER_AREA);
  }
  const double sigma_px = flatten_window_ * reduced.cols;
  const cv::Mat image = sigma_px >= 1.0 ? flattenIllumination(reduced, sigma_px, flatten_min_range_) : reduced;
  orb_->detectAndCompute(image, cv::noArray(), features.keypoints, features.descriptors);
  if (subpixel_window_ > 0 && !features.keypoints.empty()) {
    // FAST positions are whole pixels of their pyramid level; refining them to the gradient-weighted
    // corner reduces the noise of every fit that uses them.
    std::vector<cv::Point2f> corners;
    for (const auto& kp : features.keypoints) corners.push_back(kp.pt);
    cv::cornerSubPix(image, corners, cv::Size(subpixel_window_, subpixel_window_), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 10, 0.01));
    for (size_t i = 0; i < corners.size(); ++i) {
      // A refinement that wanders off the keypoint is not a refinement.
      if (cv::norm(corners[i] - features.keypoints[i].pt) <= static_cast<double>(subpixel_window_)) {
        features.keypoints[i].pt = corners[i];
      }
    }
  }
  if (reduction > 1) {
    // Reduced pixel i averages full-resolution pixels f*i .. f*i+f-1: its centre is f*(i+0.5)-0.5 there.
    const float f = static_cast<float>(reduction);
    for (auto& kp : features.keypoints) {
      kp.pt = cv::Point2f(f * (kp.pt.x + 0.5f) - 0.5f, f * (kp.pt.y + 0.5f) - 0.5f);
      kp.size *= f;
    }
  }
  return features;
}

GroundFeatures projectToGround(const ImageFeatures& features, const CameraModel& camera) {
  // Each keypoint and a point a few pixels along its ORB orientation: the two ground points give the
  // orientation on the ground, whatever the mount.
  constexpr double kArmPx = 4.0;
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(2 * features.keypoints.size());
  for (const auto& kp : features.keypoints) {
    const double angle = kp.angle * M_PI / 180.0;
    pixels.emplace_back(kp.pt.x, kp.pt.y);
    pixels.emplace_back(kp.pt.x + kArmPx * std::cos(angle), kp.pt.y + kArmPx * std::sin(angle));
  }
  const std::vector<Eigen::Vector2d> rays = camera.normalisedRays(pixels);
  GroundFeatures ground;
  ground.points.reserve(features.keypoints.size());
  for (size_t i = 0; i < features.keypoints.size(); ++i) {
    const auto p = CameraModel::intersectGround(rays[2 * i], camera.T_robot_camera());
    const auto arm = CameraModel::intersectGround(rays[2 * i + 1], camera.T_robot_camera());
    if (!p || !arm) continue;
    ground.rays.push_back(rays[2 * i]);
    const Eigen::Vector2d direction = *arm - *p;
    ground.points.push_back(*p);
    ground.descriptors.push_back(features.descriptors.row(static_cast<int>(i)));
    ground.angles_rad.push_back(static_cast<float>(std::atan2(direction.y(), direction.x())));
    ground.octaves.push_back(static_cast<std::uint8_t>(std::clamp(features.keypoints[i].octave, 0, 255)));
  }
  return ground;
}

void reprojectToGround(GroundFeatures& features, const Eigen::Isometry3d& T_robot_camera) {
  for (size_t i = 0; i < features.rays.size() && i < features.points.size(); ++i) {
    if (const auto p = CameraModel::intersectGround(features.rays[i], T_robot_camera)) features.points[i] = *p;
  }
}

GroundFeatures selectFeatures(const GroundFeatures& features, const std::vector<bool>& keep) {
  GroundFeatures kept;
  for (size_t i = 0; i < features.size(); ++i) {
    if (i < keep.size() && !keep[i]) continue;
    kept.points.push_back(features.points[i]);
    kept.descriptors.push_back(features.descriptors.row(static_cast<int>(i)));
    if (features.hasOrientations()) {
      kept.angles_rad.push_back(features.angles_rad[i]);
      kept.octaves.push_back(features.octaves[i]);
    }
    if (features.hasRays()) kept.rays.push_back(features.rays[i]);
  }
  return kept;
}

GroundFeatures dropNearTwins(const GroundFeatures& features, int max_distance) {
  if (max_distance <= 0 || features.size() < 2) return features;
  const int n = static_cast<int>(features.size());
  std::vector<bool> twin(features.size(), false);
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (cv::norm(features.descriptors.row(i), features.descriptors.row(j), cv::NORM_HAMMING) <= max_distance) {
        twin[static_cast<size_t>(i)] = twin[static_cast<size_t>(j)] = true;
      }
    }
  }
  twin.flip();  // keep the ones without a twin
  return selectFeatures(features, twin);
}

}  // namespace groundslam
