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

struct SimulationSettings {
  std::string texture_kind = "asphalt";  ///< procedural kind, unless a user texture is given
  double user_texture_width_m = 1.0;     ///< metric width of a user texture image
  PathSettings path;
  CameraIntrinsics camera = scaledHdGroundIntrinsics(320, 240);
  double mounting_height_m = 0.25;
  double mount_jitter_deg = 0.0;         ///< standard deviation of the mount's roll and pitch (smooth over time)
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
  /// The mount of frame `index`, jittered in roll and pitch.
  Eigen::Isometry3d mountAt(int index) const;
  /// The 8-bit grey image of frame `index`.
  cv::Mat renderFrame(int index) const;

 private:
  GroundTexture layTexture(const cv::Mat& user_texture) const;
  double footprintRadius() const;

  SimulationSettings settings_;
  CameraModel camera_;
  std::vector<Pose2> poses_;
  std::vector<Eigen::Vector2d> jitter_rad_;  ///< (roll, pitch) per frame
  GroundTexture dry_, wet_;
  GroundRenderer renderer_;
};

}  // namespace groundslam::sim
