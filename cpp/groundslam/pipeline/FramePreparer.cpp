#include "groundslam/pipeline/FramePreparer.hpp"

#include "groundslam/core/ImageReduction.hpp"
#include "groundslam/pipeline/StageTimer.hpp"

namespace groundslam {

CameraModel cameraModelFrom(const CameraConfig& c) {
  Eigen::Isometry3d T_robot_camera = defaultCameraMount(c.mounting_height_m);
  if (c.T_robot_camera) {
    const Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T(c.T_robot_camera->data());
    T_robot_camera.matrix() = T;
  }
  return CameraModel(intrinsicsOf(c), T_robot_camera);
}

ImageAlignmentSettings alignmentSettingsFrom(const Config& config) {
  ImageAlignmentSettings settings;
  settings.width_px = config.odometry_checks.align_width_px;
  settings.highpass_fraction = config.odometry_checks.align_highpass_fraction;
  settings.normalise_contrast = config.odometry_checks.align_normalise_contrast;
  return settings;
}

ImageAlignmentSettings headingImageSettingsFrom(const Config& config) {
  ImageAlignmentSettings settings;
  settings.width_px = config.outdoor.heading_image_width_px;
  settings.highpass_fraction = config.outdoor.heading_highpass_fraction;
  settings.normalise_contrast = true;
  settings.light_edge_slope = config.outdoor.heading_light_edge_slope;
  return settings;
}

FramePreparer::FramePreparer(const Config& config)
    : camera_(cameraModelFrom(config.camera)),
      extractor_(config.features),
      matcher_(config.matching),
      near_twin_max_distance_(config.features.near_twin_max_distance),
      decoder_reduction_(decoderReductionFor(config.camera.image_width, config.features.max_extraction_width)),
      turn_width_px_(config.fallback.turn_image_width_px) {
  if (config.odometry_checks.align_images) alignment_ = alignmentSettingsFrom(config);
  if (config.outdoor.estimate_mount && config.outdoor.track_points) tracking_ = PointTrackingSettings{};
  if (config.outdoor.heading_image_width_px > 0 && config.odometry_checks.align_heading_sigma_deg > 0.0) {
    heading_ = headingImageSettingsFrom(config);
  }
}

PreparedFrame FramePreparer::prepare(const cv::Mat& image, double timestamp, int reduced_by) const {
  // ORB keypoints and descriptors, projected to metric points on the ground plane (paper eqs. 2-4).
  StageTimer timer;
  PreparedFrame prepared;
  prepared.timestamp = timestamp;
  const ImageFeatures image_features = extractor_.detect(image, reduced_by);
  prepared.extract_ms = timer.lap();
  prepared.features = dropNearTwins(projectToGround(image_features, camera_), near_twin_max_distance_);
  if (alignment_) prepared.alignment = alignmentImage(image, *alignment_, reduced_by);
  if (tracking_) prepared.tracking = trackingImage(image, *tracking_, reduced_by);
  if (heading_) prepared.heading = alignmentImage(image, *heading_, reduced_by);
  if (turn_width_px_ > 0) {
    ReducedImage turn = reduceByWholeFactor(image, turn_width_px_);
    prepared.turn = std::move(turn.pixels);
    prepared.turn_scale = static_cast<double>(turn.factor) * std::max(1, reduced_by);
  }
  prepared.project_ms = timer.lap();
  return prepared;
}

}  // namespace groundslam

namespace groundslam {

void FramePreparer::matchToPrevious(PreparedFrame& frame, const cv::Mat& previous_descriptors) const {
  StageTimer timer;
  frame.matches_to_previous = matcher_.match(frame.features.descriptors, previous_descriptors);
  frame.match_ms = timer.lap();
}

}  // namespace groundslam
