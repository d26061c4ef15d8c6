#pragma once
// Paper §III-A, image processing: ORB keypoints and descriptors, projected to metric points on the
// ground plane. It keeps no state between images, so applications may prepare the next images on other
// threads while the back end works on the current one.

#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/ImageAlignment.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/PointTracking.hpp"
#include "groundslam/pipeline/Config.hpp"

namespace groundslam {

/// The camera model a configuration describes (default mount unless T_robot_camera is given).
CameraModel cameraModelFrom(const CameraConfig& camera);

/// An image after §III-A, ready for the rest of the pipeline.
struct PreparedFrame {
  double timestamp = 0.0;
  GroundFeatures features;
  double extract_ms = 0.0;
  double project_ms = 0.0;
  /// §III-B's matching to the previous image, done ahead (FramePreparer::matchToPrevious) so that it runs on a
  /// preparing thread instead of the back end's: only valid when the previous image is the one Slam::process
  /// was given just before this frame. Empty: Slam matches by itself.
  std::optional<std::vector<Match>> matches_to_previous;
  double match_ms = 0.0;
  /// The image reduced for aligning it with the next one where features are too few (odometry.align_images; empty when off).
  AlignmentImage alignment;
  /// The image reduced for tracking its keypoints into the next one (outdoor.track_points; empty when off).
  TrackingImage tracking;
  /// The image, contrast-normalised, that refines the heading where the robot's own artifacts are seen
  /// (outdoor.heading_image_width_px; empty when 0 or when headings are not refined).
  AlignmentImage heading;
  /// The image reduced for measuring a failed frame's turn from its spectrum (odometry.fallback_turn_image_width_px;
  /// CV_32F, empty when 0).
  cv::Mat turn;
  double turn_scale = 1.0;  ///< original image pixels per pixel of `turn` (the decoder's and this reduction)
};

/// The alignment settings a configuration describes (odometry.align_*).
ImageAlignmentSettings alignmentSettingsFrom(const Config& config);
/// The settings of the images that refine the heading where the robot's own artifacts are seen (outdoor.heading_*).
ImageAlignmentSettings headingImageSettingsFrom(const Config& config);

class FramePreparer {
 public:
  explicit FramePreparer(const Config& config);
  /// One image (8-bit grey) at a time per FramePreparer; use one each for images prepared concurrently.
  /// `reduced_by` > 1: the image was decoded already reduced by that factor (see decoderReduction()).
  PreparedFrame prepare(const cv::Mat& image, double timestamp, int reduced_by = 1) const;
  /// Matches the frame's descriptors to the previous frame's (2-NN, ratio test), as Slam would.
  void matchToPrevious(PreparedFrame& frame, const cv::Mat& previous_descriptors) const;
  /// How far a JPEG decoder may reduce this camera's images before extraction (features.max_extraction_width).
  int decoderReduction() const { return decoder_reduction_; }

 private:
  CameraModel camera_;
  OrbExtractor extractor_;
  DescriptorMatcher matcher_;
  int near_twin_max_distance_;
  int decoder_reduction_;
  std::optional<ImageAlignmentSettings> alignment_;  ///< empty: odometry.align_images is off
  std::optional<PointTrackingSettings> tracking_;    ///< empty: outdoor.track_points (or estimate_mount) is off
  std::optional<ImageAlignmentSettings> heading_;    ///< empty: outdoor.heading_image_width_px or align_heading_sigma_deg is 0
  int turn_width_px_ = 0;                             ///< odometry.fallback_turn_image_width_px
};

}  // namespace groundslam
