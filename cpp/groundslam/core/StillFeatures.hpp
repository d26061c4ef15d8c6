#pragma once
// Not in the paper: features that stay still in the image while the robot moves are not on the ground: the
// edge of the robot's own shadow, dirt on the lens, a bumper in view, the glare of the robot's lamp. Matched
// between two images they claim "no motion" and pull a fit toward it. They are found two ways: a match at
// the same place in both images when the other matches say the robot moved, and a mask of image cells where
// that keeps happening (learnt over the run, fading so that a shadow that turns away frees its cells).

#include <vector>

#include <Eigen/Core>

#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Matching.hpp"

namespace groundslam {

/// Matches whose two keypoints lie within `radius` of each other in the image (normalised ray units) and the rest.
struct StillSplit {
  std::vector<Match> still;
  std::vector<Match> moving;
};
StillSplit splitStillMatches(const std::vector<Match>& matches, const GroundFeatures& query, const GroundFeatures& train,
                             double radius);

/// Every feature of `query` with a feature of `train` at the same place in the image (within `radius`, ray
/// units) and a similar descriptor (at most `max_hamming` bits): for two frames between which the robot moved,
/// the features that moved with the camera. Unlike splitStillMatches it needs no ratio-test match, so it also
/// finds artifacts that look alike (a bumper's bolts, dirt specks). Returns (query, train) pairs.
std::vector<Match> findStillFeatures(const GroundFeatures& query, const GroundFeatures& train, double radius, int max_hamming);

struct ArtifactMaskSettings {
  int cells_x = 20;          ///< grid over the image
  int cells_y = 15;
  double fade = 0.9;         ///< evidence kept from one frame to the next
  double min_evidence = 1.5; ///< still matches (faded sum) a cell needs before it counts as an artifact
};

/// Image cells where matched features stay still while the robot moves.
class ArtifactMask {
 public:
  ArtifactMask(const CameraIntrinsics& intrinsics, const ArtifactMaskSettings& settings);
  /// One frame's evidence, for a frame whose fit says the robot moved: features of `current` (query side of
  /// the matches) that stayed still and those that moved with the ground.
  void observe(const GroundFeatures& current, const std::vector<Match>& still, const std::vector<Match>& moving);
  /// Fades the evidence of a frame that gave none (the robot stood still or tracking failed).
  void fade();
  bool isArtifact(const Eigen::Vector2d& ray) const;
  /// The features outside artifact cells (all of them when the set has no rays).
  GroundFeatures withoutArtifacts(const GroundFeatures& features) const;
  std::vector<Match> withoutArtifacts(const std::vector<Match>& matches, const GroundFeatures& query) const;
  int artifactCells() const;

 private:
  int cellOf(const Eigen::Vector2d& ray) const;
  CameraIntrinsics intrinsics_;
  ArtifactMaskSettings settings_;
  std::vector<double> still_, moving_;
};

}  // namespace groundslam
