#pragma once
// Paper §III-A: ORB keypoints and descriptors, projected to metric points on the ground plane.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "groundslam/core/CameraModel.hpp"

namespace groundslam {

/// How ORB ranks FAST corners before keeping the best num_features.
enum class OrbScore { harris, fast };

struct OrbSettings {
  int num_features = 1500;            ///< ORB keypoints kept per image
  double scale_factor = 1.2;          ///< pyramid decimation ratio
  int num_levels = 4;                 ///< pyramid levels (the camera height is fixed: few are needed)
  int fast_threshold = 5;             ///< FAST corner threshold, grey levels (low: dark wet ground still has corners)
  int patch_size = 31;                ///< BRIEF patch, pixels
  int edge_threshold = 31;            ///< border without features, pixels
  OrbScore score_type = OrbScore::harris;
  int near_twin_max_distance = 0;     ///< drop descriptors this close (Hamming) to another of the same image; 0 keeps all
  int subpixel_window = 0;            ///< half-size of the cornerSubPix window refining keypoints; 0 = off
  /// > 0: before ORB, the image's background light (a Gaussian blur whose sigma is this fraction of the image
  /// width) is subtracted, so that smooth light changes fixed in the image (a lamp's glare, vignetting, a soft
  /// shadow) do not change the descriptors of the ground passing under them. 0 = off.
  double flatten_window = 0.03;
  /// Flattening removes the ground's own slow changes too, which tells one tile of a repeated pattern from
  /// the next: it applies only to images whose background light spans this many grey levels (a lamp's
  /// glare does; vignetting and exposure changes do not), judged over areas five times flatten_window.
  double flatten_min_range = 35.0;
  /// Images wider than this are reduced by the smallest whole factor that brings them to this width or less
  /// (pixel areas averaged) before ORB; keypoints come back in full-resolution pixels. HD Ground's 0.11 mm
  /// pixels are far finer than tracking needs, and sensor noise averages out in the reduction. 0 = never.
  int max_extraction_width = 800;
};

/// The whole factor by which `image_width` is reduced before ORB (1: not at all).
int extractionReduction(int image_width, int max_extraction_width);

/// The largest of 8, 4, 2, 1 that divides the reduction: how far a JPEG decoder may shrink such an image
/// by itself (its scaled decoding averages pixel blocks, as the reduction does).
int decoderReductionFor(int image_width, int max_extraction_width);

/// Keypoints in pixels with their descriptors (row i describes keypoint i).
struct ImageFeatures {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  ///< CV_8U, 32 bytes per row
};

/// Ground points in the robot frame (metres) with their descriptors (row i describes point i). Features
/// projected from an image also carry their orientation on the ground and pyramid octave (what global
/// localization votes with); sets built otherwise may leave those two empty.
struct GroundFeatures {
  std::vector<Eigen::Vector2d> points;
  cv::Mat descriptors;
  std::vector<float> angles_rad;       ///< ORB orientation as a direction on the ground, robot frame
  std::vector<std::uint8_t> octaves;   ///< ORB pyramid level
  /// Undistorted normalised camera rays (x/z, y/z) of the keypoints: where they are in the image, whatever the
  /// mount. Kept for the frames being tracked (re-projection with an estimated mount, still features); empty in maps.
  std::vector<Eigen::Vector2d> rays;
  bool hasOrientations() const { return angles_rad.size() == points.size() && octaves.size() == points.size(); }
  bool hasRays() const { return rays.size() == points.size(); }
  size_t size() const { return points.size(); }
};

/// The image minus its background light (a Gaussian blur of `sigma_px`), around grey 128 (8-bit, saturating),
/// when the light over areas five times wider differs by `min_range` grey levels or more; else the image.
cv::Mat flattenIllumination(const cv::Mat& gray_image, double sigma_px, double min_range);

class OrbExtractor {
 public:
  explicit OrbExtractor(const OrbSettings& settings);
  /// Keypoints in the pixels of the full-resolution image. `reduced_by` > 1: the image was already reduced by
  /// that factor when decoded (it divides the extraction's own reduction).
  ImageFeatures detect(const cv::Mat& gray_image, int reduced_by = 1) const;

 private:
  cv::Ptr<cv::ORB> orb_;
  int max_extraction_width_;
  int subpixel_window_;
  double flatten_window_;
  double flatten_min_range_;
};

/// Keeps the keypoints whose ray meets the ground, as metric points (pixel keypoints are not kept).
GroundFeatures projectToGround(const ImageFeatures& features, const CameraModel& camera);

/// Recomputes the ground points from the rays for another mount (a frame's estimated tilt and height). Points
/// whose ray no longer meets the ground keep their old position. Needs rays.
void reprojectToGround(GroundFeatures& features, const Eigen::Isometry3d& T_robot_camera);

/// Removes every feature whose descriptor lies within `max_distance` of another one in the same set:
/// on repetitive floors such twins can only produce ambiguous matches.
GroundFeatures dropNearTwins(const GroundFeatures& features, int max_distance);

/// The features whose entry in `keep` is true, with everything the set has of them (rays, orientations).
GroundFeatures selectFeatures(const GroundFeatures& features, const std::vector<bool>& keep);

}  // namespace groundslam
