#pragma once
// A simulated sequence: a downward camera driven along a path over a textured plane, with exact
// ground truth. Deterministic for a seed. No file I/O: the application writes what it renders.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/Pose2.hpp"
#include "groundslam/sim/Paths.hpp"
#include "groundslam/sim/Photometry.hpp"
#include "groundslam/sim/Renderer.hpp"
#include "groundslam/sim/Texture.hpp"

namespace groundslam::sim {

/// HD Ground's camera scaled to a resolution: the same field of view on the ground.
CameraIntrinsics scaledHdGroundIntrinsics(int width, int height);

/// What an outdoor robot's camera records besides the ground: things that stay still in the image.
struct CameraArtifacts {
  double shadow = 0.0;     ///< darkness of the robot's own shadow (0: none, 1: black); its edge turns with the heading
  int lens_dirt = 0;       ///< dark blotches fixed on the lens
  double glare = 0.0;      ///< peak of a bright patch fixed in the image (the robot's lamp), albedo units; 1 saturates
  double bumper = 0.0;     ///< share of the image height hidden by a part of the robot in view (bolts, edges: strong corners)
};

/// Motion harder than the path's own: sharp turns on the spot.
struct HardMotion {
  int spin_every = 0;      ///< every this many frames the robot turns sharply by spin_deg, half a period later back (0: never)
  double spin_deg = 90.0;  ///< size of each sharp turn between two frames
};

struct SimulationSettings {
  std::string texture_kind = "asphalt";  ///< procedural kind, unless a user texture is given
  double user_texture_width_m = 1.0;     ///< metric width of a user texture image
  PathSettings path;
  CameraIntrinsics camera = scaledHdGroundIntrinsics(320, 240);
  double mounting_height_m = 0.25;
  double mount_jitter_deg = 0.0;         ///< standard deviation of the mount's roll and pitch (smooth over time)
  double height_jitter_m = 0.0;          ///< standard deviation of the camera height (smooth over time)
  CameraArtifacts artifacts;
  HardMotion motion;
  double motion_blur = 0.0;              ///< exposure time as a fraction of the frame interval
  double wet_after = 1.0;                ///< fraction of the path after which the ground is wet (1 = never)
  PhotometricSettings photometry;
  std::uint64_t seed = 1;
  /// When set, the ground is this seed's texture laid over a fixed square of `ground_size_m` centred on the
  /// world origin, whatever the path: sessions with other paths and seeds see the same ground where they
  /// overlap (a second session over a mapped floor). Unset: the texture covers the path, from `seed`.
  std::optional<std::uint64_t> ground_seed;
  double ground_size_m = 2.0;
};

class SequenceSimulator {
 public:
  /// `user_texture` (8-bit grey), when not empty, replaces the procedural texture.
  explicit SequenceSimulator(const SimulationSettings& settings, const cv::Mat& user_texture = cv::Mat());

  int frameCount() const { return static_cast<int>(poses_.size()); }
  const std::vector<Pose2>& groundTruth() const { return poses_; }
  const CameraModel& camera() const { return camera_; }
  const GroundTexture& texture() const { return dry_; }
  /// The mount of frame `index`: rotated by roll (about the robot's x) then pitch (about its y), raised by
  /// the height jitter.
  Eigen::Isometry3d mountAt(int index) const;
  /// (roll, pitch) in radians and the camera height in metres of frame `index`.
  Eigen::Vector3d mountStateAt(int index) const;
  /// The 8-bit grey image of frame `index`.
  cv::Mat renderFrame(int index) const;

 private:
  GroundTexture layTexture(const cv::Mat& user_texture) const;
  double cornerRadius() const;     ///< distance from the robot origin to the farthest image corner on the ground
  double footprintRadius() const;  ///< cornerRadius with margins for the mount's motion
  void addHardMotion();
  void prepareArtifacts();
  GroundShadow shadowAt(const Pose2& pose) const;

  SimulationSettings settings_;
  CameraModel camera_;
  std::vector<Pose2> poses_;
  std::vector<Eigen::Vector2d> jitter_rad_;  ///< (roll, pitch) per frame
  std::vector<double> height_jitter_m_;      ///< per frame
  std::vector<double> spin_rad_;             ///< heading added by sharp turns, per frame
  cv::Mat dirt_;                             ///< transmission of the lens per pixel (CV_32F), empty: clean
  cv::Mat glare_;                            ///< radiance added per pixel (CV_32F), empty: none
  cv::Mat bumper_, bumper_cover_;            ///< the robot part's radiance and coverage per pixel (CV_32F), empty: none
  Eigen::Vector2d sun_direction_world_ = Eigen::Vector2d::UnitX();
  double shadow_offset_m_ = 0.0;
  GroundTexture dry_, wet_;
  GroundRenderer renderer_;
};

/// Frames a camera drops: from each frame, with `probability`, a gap of 1 to `max_gap` frames begins.
/// Deterministic for a seed; the first and last frames are kept.
std::vector<bool> droppedFrames(int frames, double probability, int max_gap, std::uint64_t seed);

}  // namespace groundslam::sim
