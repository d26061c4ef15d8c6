#pragma once
// The SLAM system of Hart et al. (ICRA 2023), one image at a time: image processing (§III-A), local
// odometry (§III-B), loop closure (§III-C) and pose-graph optimisation.

#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/RigidFit.hpp"
#include "groundslam/core/Trajectory.hpp"
#include "groundslam/pipeline/Config.hpp"
#include "groundslam/pipeline/FrameResult.hpp"

namespace groundslam {

/// The camera model a configuration describes (default mount unless T_robot_camera is given).
CameraModel cameraModelFrom(const CameraConfig& camera);

/// A processed image: its metric ground features, all that is kept of it.
struct Keyframe {
  int index = 0;
  double timestamp = 0.0;
  GroundFeatures features;
};

/// The relative motion between consecutive frames and how it was obtained.
struct OdometryEdge {
  Pose2 T_prev_curr;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  int matches = 0;
  int inliers = 0;
  FitStatus fit_status = FitStatus::ok;
  bool fallback = false;  ///< the fit failed and the previous motion was assumed
};

class Slam {
 public:
  explicit Slam(const Config& config);

  /// Processes the next image (8-bit grey) of the sequence.
  FrameResult process(const cv::Mat& image, double timestamp);

  /// The current estimate of every processed frame's pose.
  Trajectory trajectory() const;

 private:
  Keyframe extractKeyframe(const cv::Mat& image, double timestamp, FrameResult& result) const;
  OdometryEdge estimateOdometry(const Keyframe& previous, const Keyframe& current, FrameResult& result) const;
  OdometryEdge fallbackOdometry(OdometryEdge failed) const;

  Config config_;
  CameraModel camera_;
  OrbExtractor extractor_;
  DescriptorMatcher matcher_;
  std::optional<Keyframe> previous_;
  std::optional<OdometryEdge> last_good_odometry_;
  Trajectory poses_;
};

}  // namespace groundslam
