#pragma once
// Global localization on a feature map, with no pose prior (Micro-GPS's idea on our ORB map): every query
// feature and every map feature sharing its visual word propose a full robot pose,
// T_map_robot = T_map_feature * T_robot_feature^-1, from the two positions and ORB orientations. The votes
// land in a sparse (x, y, theta) grid; the strongest peaks are verified by the robust SE(2) fit of their
// correspondences, then by guided re-matching against every map feature in the predicted footprint. A peak
// is accepted only when the map confirms it clearly better than any other verified pose (on tiles, the
// runner-up sits one period away), with enough inliers spread over the image and a tight covariance.

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Pose2.hpp"
#include "groundslam/core/RigidFit.hpp"
#include "groundslam/localization/FeatureMap.hpp"

namespace groundslam {

struct LocalizationSettings {
  double cell_m = 0.01;              ///< vote cell size in x and y
  double cell_deg = 6.0;             ///< vote cell size in heading
  int max_hamming = 64;              ///< a map feature votes only when its descriptor is this close, bits
  int max_postings = 400;            ///< words with more map features than this are too common to vote
  int max_peaks = 4;                 ///< peaks verified, strongest first
  int min_votes = 8;                 ///< a peak with fewer votes is not verified
  double max_rival_ratio = 0.5;      ///< inliers of the best rival pose / the winner's, at most
  double max_vote_ratio = 0.7;       ///< votes of the strongest other peak / the winner's, at most
  /// The same where the floor shows no repetition: no rival pose verified with min_inliers inliers (and, in a run,
  /// odometry never met a rival repetition). There a weak winner's dozen votes are matched by chance peaks, while
  /// its verified inliers still decide (1 = votes not compared).
  double unrepeated_max_vote_ratio = 1.0;
  int min_inliers = 30;              ///< after guided re-matching
  /// Of them, at least min_strong_inliers must have descriptors within strong_hamming bits: guided re-matching pairs
  /// a feature with a lone map feature nearby whatever its descriptor, so on a dense map nearness alone confirms any
  /// pose. True matches agree as matches do (measured outdoors: 17-96 within 40 bits); pairs of nearness, hardly any.
  int strong_hamming = 40;
  int min_strong_inliers = 15;
  double max_covariance_score = -4.0;  ///< log10 of the largest eigenvalue of the fit's covariance
  double min_spread = 0.25;          ///< inliers must span this fraction of the query features' extent (both axes)
  double match_radius_m = 0.004;     ///< guided re-matching radius around the predicted position
  double ratio = 0.8;                ///< ratio test of the guided re-matching
  double footprint_radius_m = 0.25;  ///< map anchors this close to the predicted pose supply the re-matching
  /// A relocalization while lost is accepted when two localizations agree with odometry within these.
  double max_odometry_disagreement_m = 0.01;
  double max_odometry_disagreement_rad = 0.035;
  int every_frames = 10;  ///< on a prior map, a tracked frame is localized on it this often (a loop closure)
  /// While tracking (lost, or on a prior map), a localization this close to a map keyframe's own pose, and
  /// within min_anchor_offset_rad of its heading, is refused: features fixed to the camera (the robot's shadow,
  /// dirt, bumper) left in a keyframe put every later image there, while a true revisit lands exactly on a
  /// keyframe's pose almost never. So is a loop closure that puts the current frame this close to the earlier one's
  /// pose (its gate `still`).
  double min_anchor_offset_m = 0.003;
  double min_anchor_offset_rad = 0.0175;
  /// On a floor that repeats, a relocalization is confirmed only by localizations of frames at least this far apart by
  /// odometry: two images of nearly the same ground match the same repetition as readily as the right place (0: any).
  double repeated_floor_baseline_m = 0.05;
  /// A localization becomes a graph edge from the nearest map keyframe; the edge is measured again on that keyframe's
  /// own features, as a loop closure would be. Across a map bent by its drift, the features of several keyframes
  /// agree with a pose a few degrees off any one of them.
  bool measure_on_keyframe = true;
};

enum class LocalizationStatus { localized, too_few_votes, ambiguous, too_few_inliers, covariance, clustered };
const char* localizationStatusName(LocalizationStatus status);

struct Localization {
  LocalizationStatus status = LocalizationStatus::too_few_votes;
  Pose2 T_map_robot;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  ///< of T_map_robot (x, y, theta)
  int votes = 0;            ///< the winning peak's votes (its neighbourhood)
  int runner_up_inliers = 0;  ///< inliers of the best verified pose away from the winner
  int runner_up_votes = 0;    ///< votes of the strongest other peak
  int inliers = 0;
  int strong_inliers = 0;   ///< of them, those whose descriptors agree within settings.strong_hamming bits
  int anchor = -1;          ///< the map anchor nearest the pose (for a graph edge)
  Pose2 T_anchor_robot;     ///< the pose relative to that anchor
  Eigen::Matrix3d anchor_covariance = Eigen::Matrix3d::Identity();  ///< of T_anchor_robot
  bool ok() const { return status == LocalizationStatus::localized; }
};

/// `T_a_b` puts frame b on frame a's own pose, within settings.min_anchor_offset_*: what features fixed to the camera
/// (the robot's shadow, lens dirt, bumper) say of any two frames.
bool onTheEarlierPose(const Pose2& T_a_b, const LocalizationSettings& settings);

/// Which anchors may vote: e.g. only those of segments other than the lost one.
using AnchorFilter = std::vector<bool>;

/// Localizes features seen by the robot (robot frame, with orientations) on the map. `usable`, when not
/// empty, says per anchor whether its features may vote. Failure is a status, never an exception.
Localization localizeGlobally(const FeatureMap& map, const GroundFeatures& query, const LocalizationSettings& settings,
                              const FitSettings& fitting, const AnchorFilter& usable = {});

}  // namespace groundslam
