#pragma once
// Paper §III-C: loop closure. Frame n-k enters the bag-of-words database when frame n arrives; frame n
// queries it, and the best few candidates by BoW score must pass three gates, cheapest first:
// BoW score, number of matched keypoints, and the covariance score of the robust fit. Only frames that
// cover new ground are kept as places (PlaceMap), so the cost of a frame does not grow with the run.

#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <cmath>
#include <vector>

#include "groundslam/core/Pose2.hpp"

#include <Eigen/Core>

#include "groundslam/bow/BowDatabase.hpp"
#include "groundslam/bow/Vocabulary.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/RigidFit.hpp"
#include "groundslam/localization/FeatureMap.hpp"
#include "groundslam/localization/GlobalLocalizer.hpp"
#include "groundslam/pipeline/PlaceMap.hpp"

namespace groundslam {

/// The segment tied to the map frame: the run's first frames (or a prior map's keyframes). A lost segment
/// joins it when it relocalizes.
constexpr int kMapSegment = 0;
/// Frames given up when the map started again (Slam::restartMap).
constexpr int kAbandonedSegment = -1;

struct LoopClosureSettings {
  bool enabled = true;               ///< false: odometry only
  int database_delay_frames = 20;    ///< k: frame n-k enters the database when frame n arrives
  int max_candidates = 4;            ///< candidates near the estimate verified per frame, best BoW scores first
  int max_nearby_places = 16;        ///< the nearest places within reach are BoW-scored; the best become candidates
  int max_global_candidates = 1;     ///< further candidates from the whole database (the paper's search)
  int max_accepted_per_frame = 1;    ///< verification stops once this many candidates of a frame are accepted
  double loop_spacing_m = 0.03;      ///< after an accepted loop closure, the search rests until the robot drove this far
  double search_radius_m = 0.25;     ///< frames this close to the estimate (plus the drift allowance) are near
  double max_search_radius_m = 0.5;  ///< cap on that reach; larger drift is left to the global search
  double place_spacing_m = 0.03;     ///< a frame becomes a place unless one lies this close (positions only)
  double min_bow_score = 0.04;       ///< gate 1
  int min_matches = 30;              ///< gate 2: ratio-test matches between the two frames
  int min_inliers = 25;              ///< gate 3: a loop fit with fewer inliers has failed (unbounded covariance)
  double max_covariance_score = -4.0;  ///< gate 3: log10 of the largest eigenvalue of the fit's covariance
  double max_ambiguity = 0.8;        ///< also gate 3: rival transform's support / the fit's (repetitive floors)
  /// A loop transform may disagree with the current estimate of T_a_b by at most base + rate * d, where d
  /// is the path length over which drift could have built up between a and b (through a recent loop closure).
  double max_disagreement_m = 0.015;
  double max_disagreement_per_m = 0.005;
  double max_disagreement_rad = 0.035;
  double max_disagreement_rad_per_m = 0.01;
  /// Not in the paper: an accepted loop's keypoint pairs are tracked into the place's image (Lucas-Kanade, as for
  /// the mount's points, core/PointTracking.hpp) and the transform refitted on the tracked points. ORB keypoints
  /// scatter by most of a pixel, tracked ones by a few hundredths; a loop's heading was off by 0.05-0.4 degrees.
  bool refine_by_tracked_points = true;
  /// How far a frame's estimated tilt is off (degrees, each of roll and pitch): its effect on a refined loop's
  /// transform, which the tracked points' own residuals do not show, is added to the loop's covariance.
  double tilt_sigma_deg = 0.2;
  /// Not in the paper: a candidate that fails gate 3 for too few inliers or a loose covariance, whose matches still
  /// agree on one transform with at least this many inliers (and no rival), is measured again by its keypoints
  /// tracked into the place's image (refine_by_tracked_points) and accepted when the tracked points pass gate 3
  /// themselves: on a fine texture such as carpet the ratio test keeps a few dozen of the keypoints' matches, and
  /// a handful of inliers among them. Not on a floor seen to repeat. 0: off.
  int rescue_min_inliers = 8;
  /// Not in the paper: while tracking is lost on a floor that does not repeat, a lost frame whose global localization
  /// failed is also verified, as a loop closure is, against the map's places near its estimate, which the unknown
  /// motion at the loss (frames dropped, a turn) may have moved by up to lost_reach_m and lost_reach_deg more than
  /// drift would. Only for a segment lost right after a frame of the map. Two such frames must agree with odometry
  /// before the segment joins the map. 0: off.
  double lost_reach_m = 0.08;
  double lost_reach_deg = 20.0;
  /// Not in the paper: once the mounts are solved over the whole run (outdoor.smooth_mount), every loop is fitted
  /// again through its frames' final mounts and the graph optimised again (pipeline/SlamLoopRefinement.cpp).
  bool remeasure_at_end = true;
};

/// Which gate a candidate failed ("" when accepted). `still`: the fit puts the current frame on the earlier frame's own
/// pose (LocalizationSettings::min_anchor_offset_*), as features fixed to the camera do.
enum class LoopGate { none, bow_score, matches, covariance, ambiguous, still };
const char* loopGateName(LoopGate gate);

/// One verified candidate: frame_a (earlier) against frame_b (current).
struct LoopCandidate {
  int frame_a = 0;
  int frame_b = 0;
  double bow_score = 0.0;
  int matches = -1;                    ///< -1 when gate 1 rejected it, or a motion between the frames was unsure
  double covariance_score = std::nan("");  ///< NaN when not fitted, +inf when the fit failed
  int inliers = 0;
  double ambiguity = std::nan("");     ///< rival transform's support / the fit's; NaN when not fitted
  double correction_m = std::nan("");  ///< how far the fitted T_a_b moves b from the map's estimate (when fitted)
  LoopGate rejected_by = LoopGate::none;
  Pose2 T_a_b;                         ///< pose of b's robot in a's robot frame (when fitted)
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  /// Gate 3 failed, yet the matches agree on this transform (LoopClosureSettings::rescue_min_inliers): a caller
  /// with the images may measure the loop again from it.
  std::optional<Pose2> coarse_T_a_b;
  bool accepted() const { return rejected_by == LoopGate::none; }
};

/// What came of a lost frame's global localization (LoopCloser::relocalize): the segment joined the map with it;
/// it waits for the next localization to confirm it (or it replaced one that the odometry since did not confirm);
/// it put the frame on a map keyframe's own pose (what stays in the image; refused); it failed (the status says why);
/// it failed but the map's places near the frame's estimate joined the segment (LoopClosureSettings::lost_reach_m).
enum class RelocalizationOutcome { joined, pending, on_a_keyframe, not_localized, joined_nearby };
const char* relocalizationOutcomeName(RelocalizationOutcome outcome);

/// One lost frame's global localization on the map and what came of it: where a robot never relocalizes, these say
/// why (e.g. `ambiguous` on a floor that repeats, `too_few_votes` off the mapped ground).
struct RelocalizationAttempt {
  int frame = 0;  ///< as LoopCandidate's frames
  Localization localization;
  RelocalizationOutcome outcome = RelocalizationOutcome::not_localized;
};

class LoopCloser {
 public:
  LoopCloser(const LoopClosureSettings& settings, std::shared_ptr<const Vocabulary> vocabulary,
             const MatcherSettings& matching, const FitSettings& fitting, const LocalizationSettings& localization);

  /// Verifies frame `frame`'s candidates against the database, then lets frame - k into it. `estimates`
  /// holds the current pose estimate of every frame up to this one; `segment` is the frame's tracking
  /// segment (a new one starts when tracking is lost; prior-guided candidates never cross segments, whose
  /// relative drift is unknown). Returns every candidate verified.
  std::vector<LoopCandidate> process(int frame, int segment, const GroundFeatures& features, const std::vector<Pose2>& estimates);
  /// While tracking is lost: localizes the frame globally on the keyframes of the map segment (no prior;
  /// another lost segment has a frame of its own and cannot place this one). A localization is accepted
  /// when the next one agrees with odometry; then both are returned as loop candidates (frame_a: the map
  /// keyframe, frame_b: the lost frame) and the frame's segment joins the map segment.
  /// When global localization fails, the frame is verified against the map's places near its estimate instead
  /// (LoopClosureSettings::lost_reach_m), with the same confirmation by the next accepted one.
  std::vector<LoopCandidate> relocalize(int frame, const GroundFeatures& features, const std::vector<Pose2>& estimates);
  /// After a lost segment joined the map: the segments lost before it that never joined (tracking was lost
  /// again first) are localized on the map now, which may have grown onto their ground. A segment joins when
  /// two of its map keyframes localize in agreement with its odometry; both localizations are returned.
  std::vector<LoopCandidate> joinOrphanSegments(const std::vector<Pose2>& estimates);
  /// Segment `from` joins segment `to` (a relocalization, or a bridge over the loss): its frames and map keyframes
  /// belong to `to` from now on.
  void joinSegments(int from, int to);
  /// The run's odometry met a rival repetition: from now on the floor is taken to repeat, and global localization
  /// compares the winner's votes with its rivals' (LocalizationSettings::max_vote_ratio, not unrepeated_max_vote_ratio).
  void floorRepeats() { floor_repeats_ = true; }
  /// The motion into the next frame given to process() may be one repetition off (Slam: on a floor whose images
  /// repeat, a motion not vouched for whose inliers fell): no prior-guided loop closure spans it.
  void motionUnsure() { next_motion_unsure_ = true; }
  /// Tracking was lost after the last frame processed: the frames still waiting their k frames become places
  /// and map keyframes at once. The delay keeps neighbours from closing loops, and across a loss there are no
  /// neighbours (candidates never cross segments); relocalization can then find the ground seen just before,
  /// which is where a robot usually is after a gap.
  void trackingLost(const std::vector<Pose2>& estimates);
  /// Tracking was lost after the last frame processed, and the map starts again with the next frame: the
  /// frames so far belong to no segment (kAbandonedSegment); they are never loop candidates nor localized onto.
  void abandonMap(const std::vector<Pose2>& estimates);
  /// Removes from frame `frame`'s features, while it still waits to become a place, those at these points
  /// (exactly: the caller's copies of the same features), e.g. ones found later to stay still in the image.
  void forgetPendingFeatures(int frame, const std::vector<Eigen::Vector2d>& points);
  /// Takes a prior map (a map file of an earlier session): its keyframes are frames 0..K-1 of segment 0,
  /// before any frame of this session.
  void adoptPriorMap(const FeatureMap& prior);
  /// While tracking on a prior map: localizes the frame on the prior map's keyframes (frames below
  /// `prior_frames`); accepted when it agrees with the current estimate up to the drift since the last
  /// correction, and returned as a loop candidate.
  std::optional<LoopCandidate> localizeOnPriorMap(int frame, const GroundFeatures& features, const std::vector<Pose2>& estimates,
                                                  int prior_frames);
  int segmentOf(int frame) const { return segment_of_frame_[static_cast<size_t>(frame)]; }
  /// Moves the places and map anchors of frames from `first_moved` on to their current estimates, after an
  /// optimisation moved them.
  void mapMoved(const std::vector<Pose2>& estimates, int first_moved);
  /// A candidate process() rejected was accepted after all (rescued by the images): the search rests after it as
  /// after any accepted loop.
  void loopRescued(const LoopCandidate& candidate);
  const PlaceMap& places() const { return places_; }
  const FeatureMap& featureMap() const { return feature_map_; }
  /// Every global localization of a lost frame so far (relocalize), in order.
  const std::vector<RelocalizationAttempt>& relocalizationAttempts() const { return relocalization_attempts_; }

 private:
  /// A frame waiting its k frames before it may become a place.
  struct Pending {
    int frame = 0;
    GroundFeatures features;  ///< with orientations, for the feature map
    BowVector bow;
  };
  /// False while the search rests after an accepted loop closure (loop_spacing_m).
  bool searchDue() const;
  /// Selects this frame's candidates and verifies them, best first, until enough are accepted.
  std::vector<LoopCandidate> verifyCandidates(int frame, const GroundFeatures& features, const BowVector& bow,
                                              const std::vector<Pose2>& estimates);
  std::vector<BowMatch> selectCandidates(int frame, const BowVector& bow, const std::vector<Pose2>& estimates) const;
  /// Lets the frames waiting up to `last` into the database and the feature map.
  void admitPlaces(int last, const std::vector<Pose2>& estimates);
  LoopCandidate verify(int frame_a, const GroundFeatures& a, int frame_b, const GroundFeatures& b, double bow_score,
                       const TransformPrior& prior, const FitSettings& fitting) const;
  /// For a candidate that failed gate 3: the transform its matches agree on with at least rescue_min_inliers
  /// inliers and no rival (LoopCandidate::coarse_T_a_b), if any.
  std::optional<Pose2> coarseTransform(const RigidEstimate& fit, const std::vector<Eigen::Vector2d>& points_a,
                                       const std::vector<Eigen::Vector2d>& points_b, const TransformPrior& prior,
                                       FitSettings fitting) const;
  /// The estimated T_a_b and how far drift since the last correction may have moved it.
  TransformPrior priorOf(int frame_a, int frame_b, const std::vector<Pose2>& estimates) const;
  /// The path length over which the estimate of T_a_b could have drifted: between a and b, or through
  /// one of the recent loop closures, whichever is shortest.
  double driftPathLength(int frame_a, int frame_b) const;

  /// A localization of a lost frame, waiting for the next one to agree with odometry.
  struct PendingLocalization {
    int frame = 0;
    Localization localization;
    GroundFeatures features;  ///< the frame's, for measuring the edge on the map keyframe (empty: not measured again)
  };
  LoopCandidate candidateFrom(const Localization& localization, int frame) const;
  /// The localization as a graph edge from its map keyframe, measured on that keyframe's own features when they
  /// confirm it (LocalizationSettings::measure_on_keyframe); else as localized on the whole map.
  LoopCandidate edgeOf(const PendingLocalization& found) const;
  /// On a floor that repeats, two localizations confirm each other only from frames this far apart
  /// (LocalizationSettings::repeated_floor_baseline_m): images of nearly the same ground are one piece of evidence.
  bool farEnoughApart(int frame_a, int frame_b, const std::vector<Pose2>& estimates) const;
  /// The lost frame against the map's places near its estimate, within the reach of the loss's unknown motion.
  std::vector<LoopCandidate> rejoinNearby(int frame, const GroundFeatures& features, const std::vector<Pose2>& estimates);
  /// The segment began right after a frame of the map segment: one unknown motion lies between them.
  bool lostFromTheMap(int segment) const;
  /// Two localizations of one segment's frames agree with what its odometry measured between them.
  bool agreeWithOdometry(const PendingLocalization& a, const PendingLocalization& b, const std::vector<Pose2>& estimates) const;
  /// A localization on a map keyframe's own pose (LocalizationSettings::min_anchor_offset_*): camera artifacts.
  bool onAnAnchorsPose(const Localization& localization) const;
  /// A global localization on the usable map keyframes, with the vote rule of the floor seen so far.
  Localization localizeOnMap(const GroundFeatures& features, const AnchorFilter& usable) const;

  LoopClosureSettings settings_;
  LocalizationSettings localization_;
  std::shared_ptr<const Vocabulary> vocabulary_;
  FeatureMap feature_map_;
  std::vector<int> segment_of_frame_;
  std::optional<PendingLocalization> pending_localization_;
  std::optional<LoopCandidate> pending_rejoin_;  ///< an accepted nearby verification, waiting for the next to agree
  bool floor_repeats_ = false;
  double matching_ratio_;
  FitSettings fitting_;
  /// For a lost frame against the map near its estimate: only shifted copies of the fit are its rivals. Over the
  /// narrow strip two footprints share after a gap, the fit turned by a few degrees about it explains nearly as many.
  FitSettings rejoin_fitting_;
  PlaceMap places_;
  std::deque<Pending> pending_;        ///< the last k frames, not yet in the map
  std::vector<double> path_length_m_;  ///< estimated distance driven up to each frame
  std::vector<int> unsure_motions_;    ///< motions that may be a repetition off, up to each frame (motionUnsure)
  bool next_motion_unsure_ = false;
  std::deque<std::pair<int, int>> recent_loops_;  ///< (frame_a, frame_b) of the latest accepted loop closures
  std::vector<RelocalizationAttempt> relocalization_attempts_;
};

}  // namespace groundslam
