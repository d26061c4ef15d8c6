#pragma once
// The SLAM system of Hart et al. (ICRA 2023), one image at a time: image processing (§III-A), local
// odometry (§III-B), loop closure (§III-C) and pose-graph optimisation.

#include <deque>
#include <map>
#include <functional>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "groundslam/bow/Vocabulary.hpp"
#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/MotionPrior.hpp"
#include "groundslam/core/MountEstimation.hpp"
#include "groundslam/core/MountSmoother.hpp"
#include "groundslam/core/PoseGraph.hpp"
#include "groundslam/core/RigidFit.hpp"
#include "groundslam/core/StillFeatures.hpp"
#include "groundslam/core/Trajectory.hpp"
#include "groundslam/pipeline/Config.hpp"
#include "groundslam/pipeline/FramePreparer.hpp"
#include "groundslam/pipeline/FrameResult.hpp"
#include "groundslam/pipeline/LoopClosure.hpp"

namespace groundslam {

/// A processed image: its metric ground features, all that is kept of it.
struct Keyframe {
  int index = 0;
  double timestamp = 0.0;
  GroundFeatures features;  ///< with rays; points projected with `mount`
  MountState mount;
};

/// The relative motion between consecutive frames and how it was obtained.
struct OdometryEdge {
  Pose2 T_prev_curr;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  int matches = 0;
  int inliers = 0;
  FitStatus fit_status = FitStatus::ok;
  bool fallback = false;  ///< the fit failed and the previous motion was assumed
  std::vector<Match> used;  ///< the matches the fit used (still ones left out)
  double rms_residual_m = 0.0;  ///< of the fit's inliers
  bool low_overlap = false;  ///< measured by the second, looser matching (OdometryChecks::low_overlap_ratio)
  bool aligned = false;      ///< measured by aligning the two images (OdometryChecks::align_images)
  bool unconfirmed = false;  ///< fitted on fewer than align_confirm_below_inliers inliers the images did not confirm
  bool turn_measured = false;  ///< a fallback whose turn was measured: by the refused fit or by the images' spectra
};

/// Whether a loss for `failed` may be bridged to the last tracked frame (Slam::bridgeLoss): a loss for too little
/// evidence, for the robot's speed or for a fit that left everything in place, on a floor whose fits show no rival
/// repetition (showsARepetition); for the speed not where the images show the floor repeating either (a gap of
/// unknown length lands one repetition short as readily as right); as ambiguous only where neither shows one (then a
/// rival had fewer inliers than a fit needs, a weak floor, not a repetition; or few matches agreed across a gap).
bool bridgeableLoss(FitStatus failed, bool fits_show_repetition, bool images_show_repetition);

class Slam {
 public:
  /// `vocabulary` may be null when loop closure is disabled in the configuration. Throws
  /// std::invalid_argument("section.key: ...") when the configuration is unusable (validateConfig).
  Slam(const Config& config, std::shared_ptr<const Vocabulary> vocabulary);

  /// Starts the session on a prior map (a map file of an earlier session), before the first frame: its
  /// keyframes become held graph poses, the session starts lost and localizes globally on the map, then
  /// tracks and closes loops against it. Every pose comes out in the map's frame. Needs loop closure.
  void usePriorMap(const FeatureMap& prior);
  /// The feature map of global localization (null when loop closure is disabled), and the segment whose
  /// keyframes are tied to the map frame (what a map file keeps).
  const FeatureMap* featureMap() const { return loop_closer_ ? &loop_closer_->featureMap() : nullptr; }
  int mapSegment() const { return kMapSegment; }

  /// Processes the next image (8-bit grey) of the sequence: prepareFrame, then process.
  FrameResult process(const cv::Mat& image, double timestamp);
  /// Image processing alone (§III-A). It reads no state that process() changes, so an application may
  /// prepare the next frame on another thread while process() runs (one prepareFrame at a time; more at
  /// once need a FramePreparer each).
  PreparedFrame prepareFrame(const cv::Mat& image, double timestamp) const { return preparer_.prepare(image, timestamp); }
  /// Odometry, loop closure and optimisation (§III-B, §III-C) of a prepared frame.
  FrameResult process(PreparedFrame frame);
  /// Optimises the whole graph once more if anything changed since its last full optimisation.
  void finish();
  /// The loop closer's places (null when loop closure is disabled).
  const PlaceMap* places() const { return loop_closer_ ? &loop_closer_->places() : nullptr; }

  /// The configuration it runs with (as validated by the constructor).
  const Config& config() const { return config_; }
  /// The current estimate of every processed frame's pose (after finish(), corrected for the whole run's mount states).
  Trajectory trajectory() const;
  /// The camera's roll, pitch and height of a frame (FrameResult::index), as finish() solved them over the whole
  /// run; before finish(), or when outdoor.smooth_mount is off, the ones the frame was processed with.
  MountState finalMount(int index) const;
  /// A frame's odometry motion from the previous frame (FrameResult::odometry) as the mounts finalMount()
  /// gives make it: the same images, with both frames' ground re-projected (unchanged before finish()). One of the
  /// run's first frames, measured while the heading images learnt their precision, with its heading refined by them
  /// as its graph edge was once that precision was known.
  Pose2 finalOdometry(int index, const Pose2& odometry) const;
  /// After finish(): how the mount was found to rock and bounce over the run (the smoother's priors); nothing
  /// when the mount was not solved over the run.
  std::optional<MountRocking> mountRocking() const { return mount_rocking_; }
  /// After finish(): whether the mounts solved over the run were used (see outdoor.smooth_mount).
  bool mountSmoothed() const { return !final_mounts_.empty(); }
  const PoseGraph& graph() const { return graph_; }
  /// Every loop-closure candidate verified so far, accepted or not (frames as in FrameResult::index); empty
  /// when an observer took them without keeping them.
  const std::vector<LoopCandidate>& loopCandidates() const { return candidates_; }
  /// Every global localization of a lost frame so far and what came of it (empty without loop closure).
  const std::vector<RelocalizationAttempt>& relocalizationAttempts() const;
  /// Each verified candidate goes to `observer` as it is decided (a long-running program can write or count
  /// them as they come); with `keep` false Slam no longer stores them, so memory does not grow with them.
  void setCandidateObserver(std::function<void(const LoopCandidate&)> observer, bool keep);

 private:
  OdometryEdge estimateOdometry(const Keyframe& previous, const Keyframe& current, const PreparedFrame& prepared, FrameResult& result);
  /// Two images of one kind an alignment compares (sharing the frames' pixels, or made from them), how they were made,
  /// and the least correlation that believes their alignment.
  struct ImagePair {
    AlignmentImage before, now;
    const ImageAlignmentSettings* settings = nullptr;
    double min_correlation = 0.0;
    double rest_ratio = 0.0;  ///< how many times better than rest (and any rival) the alignment must explain the images
    bool empty() const { return before.pixels.empty() || now.pixels.empty(); }
  };
  /// The previous frame's images and this one's that odometry aligns, in the order tried: the alignment's reduced
  /// images where they clearly tell the motion from rest (kClearlyBetterThanRest times odometry.align_rest_ratio); the
  /// contrast-normalised heading images less the mean of the recent ones (once kHeadingBackgroundImages were seen) and
  /// as they are (odometry.align_heading_images_min_correlation); the reduced images again, believed as any alignment.
  std::vector<ImagePair> odometryImagePairs(const PreparedFrame& prepared) const;
  /// The same pairs from two frames' reduced and heading images.
  std::vector<ImagePair> imagePairs(const AlignmentImage& reduced_before, const AlignmentImage& heading_before,
                                    const AlignmentImage& reduced_now, const AlignmentImage& heading_now) const;
  static constexpr double kClearlyBetterThanRest = 2.0;
  /// Where the features are too few: the motion from aligning the previous images with this frame's (each pair of
  /// odometryImagePairs in turn), started from the robot's usual steps and from several times as many
  /// (odometry.align_*; an alignment with a rival is not believed), or nothing (pipeline/SlamAlignment.cpp).
  std::optional<OdometryEdge> odometryByAlignment(const Keyframe& previous, const Keyframe& current, const PreparedFrame& prepared) const;
  /// One pair's alignment from the usual steps (odometryByAlignment), kept when plausible and moving the robot.
  std::optional<OdometryEdge> alignedFromSteps(const ImagePair& images, const Keyframe& previous, const Keyframe& current) const;
  /// False when an aligned motion over `steps` frames leaves the robot nearly where it was without a sharp turn
  /// (odometry.align_min_step_share of the usual step, per frame, and at least a still feature's reach).
  bool movedTheRobot(const Pose2& T_prev_curr, int steps = 1) const;
  /// A fit that leaves every match in place, or an alignment every keypoint, while the images' spectra show the
  /// ground moving (odometry.rest_check_by_spectra): the motion the images measure from there (`aligned`), else a fallback
  /// (FitStatus::still) assuming the spectra's motion. None when rest stands.
  std::optional<OdometryEdge> restRefuted(const Keyframe& previous, const Keyframe& current, const OdometryEdge& odometry,
                                          const PreparedFrame& prepared) const;
  /// A fit refused for too little evidence, measured again near the motion the images' spectra show
  /// (odometry.gap_by_spectra): where that motion spans frames dropped, by the features matched near it
  /// (`low_overlap`); else, or failing that, by the images aligned from it (`aligned`). None when the spectra show
  /// nothing or neither stays with them, or on a floor that repeats.
  std::optional<OdometryEdge> gapBySpectra(const Keyframe& previous, const Keyframe& current, const OdometryEdge& odometry,
                                           const PreparedFrame& prepared) const;
  /// The images aligned from the spectra's motion (each pair of odometryImagePairs in turn), kept when believable,
  /// within align_sigma_m and 1 degree of it, plausible and moving the robot (`aligned`); none otherwise.
  std::optional<OdometryEdge> alignedFromSpectra(const Keyframe& previous, const Keyframe& current, const Pose2& by_spectra,
                                                 const PreparedFrame& prepared) const;
  /// The first of `pairs` whose alignment from `by_spectra` is believable, within align_sigma_m and `turn_apart_rad`
  /// of it, moving the robot over `steps` frames and `plausible` (if given).
  std::optional<Pose2> alignedNear(const Pose2& by_spectra, const std::vector<ImagePair>& pairs, int steps,
                                   const std::function<bool(const Pose2&)>& plausible = {}, double turn_apart_rad = M_PI / 180.0) const;
  /// Whether a measured motion stays within align_sigma_m and `turn_apart_rad` of the spectra's.
  bool withTheSpectra(const Pose2& by_spectra, const Pose2& T_prev_curr, double turn_apart_rad = M_PI / 180.0) const;
  /// A motion the robot's usual step does not explain: frames dropped (at least kGapSteps usual steps long).
  bool unlikeTheRobotsStep(const Pose2& T_prev_curr) const;
  /// What the images say of a fit: not checked (enough inliers), it agrees, the aligned motion replaces it, or nothing.
  struct FitCheck {
    enum class Outcome { not_checked, confirmed, replaced, unconfirmed } outcome = Outcome::not_checked;
    Pose2 aligned_motion;  ///< T_prev_curr the images measured, when replaced
  };
  /// A fit with fewer than odometry.align_check_below_inliers inliers, checked by aligning the images from its motion
  /// (odometry.align_check_*). On a floor that repeats the images only confirm (its rivals judge the fit).
  FitCheck checkedByAlignment(const Pose2& fitted, int inliers, const std::vector<Match>& used, const Keyframe& previous,
                              const Keyframe& current, const AlignmentImage& alignment, bool repeated_floor) const;
  struct HeadingImages;
  /// The odometry's heading refined by aligning `previous` and `image` (images of `source`'s kind) from its motion
  /// (odometry.align_heading_sigma_deg); the translation follows so that the current inliers' centroid stays where
  /// the fit put it. True when the images contradict a weak fit (fewer than odometry.align_check_below_inliers
  /// inliers): aligned, they end within align_check_m of its translation but beyond align_check_rad of its heading.
  /// The fit is then left as it is, and is not `ok`.
  bool refineHeadingByImages(OdometryEdge& odometry, const Keyframe& current, const AlignmentImage& previous,
                             const AlignmentImage& image, HeadingImages& source);
  /// What the images say of a motion measured from the features, T_a_b (a: the earlier frame, its image and mount
  /// given): the images' motion relative to T_a_b, or nothing when the alignment fails (no convergence, correlation
  /// below odometry.align_min_correlation).
  std::optional<Pose2> imageMotionDifference(const Pose2& T_a_b, const AlignmentImage& image_a, const MountState& mount_a,
                                             const AlignmentImage& image_b, const MountState& mount_b,
                                             const ImageAlignmentSettings& settings) const;
  /// An edge measured by aligning the images: T_prev_curr with odometry.align_sigma_* as its covariance.
  OdometryEdge alignedEdge(const Pose2& T_prev_curr) const;
  /// The edge of a fit measured on a second look at a low-overlap pair (`low_overlap`): `used` its matches, `matches`
  /// the frame's ratio-test matches; low_overlap_sigma_m and low_overlap_sigma_rad added to its covariance.
  OdometryEdge lowOverlapEdge(const RigidEstimate& fit, std::vector<Match> used, int matches) const;
  /// An alignment that passes odometry.align_* (correlation of at least `min_correlation`, `rest_ratio` times better
  /// than rest and any rival, probes' spread).
  bool believable(const ImageAlignment& aligned, double min_correlation, double rest_ratio) const;
  /// What an alignment of images judged by `min_correlation` and `rest_ratio` must clear to be believed.
  AlignmentBar alignmentBar(double min_correlation, double rest_ratio) const;
  /// The pair's images aligned from each start, probed only where the pair's bar can be cleared.
  ImageAlignment alignPair(const ImagePair& images, const std::vector<cv::Matx23d>& starts) const;
  /// Image warps where `steps` of the robot's usual steps put the ground; with `more_steps`, also where up to
  /// repetition_max_steps times as many do.
  std::vector<cv::Matx23d> stepStarts(int steps, bool more_steps) const;
  /// Aligns from stepStarts (an alignment with a rival is not believed), or failing that from the few turns on the
  /// spot that make the images most alike.
  std::optional<ImageAlignment> alignFromSteps(const ImagePair& images, int steps, bool more_steps) const;
  /// The alignment's reduced images of `before` and `now` (odometry.align_min_correlation).
  ImagePair reducedImages(const AlignmentImage& before, const AlignmentImage& now) const;
  /// Right after tracking was lost (within odometry.bridge_max_frames frames): the current frame measured against
  /// the last tracked one joins the segment to the map, as a relocalization would (the map may not reach where the
  /// robot goes, and weak floors give global localization too little); when that frame is of a lost segment, the
  /// new segment continues that one instead. By its features first, else by its image, else by searching the motions
  /// the robot can have made, else by a weak feature fit that agrees with the lost segment's own estimate.
  void bridgeLoss(const Keyframe& current, const PreparedFrame& prepared, FrameResult& result);
  /// A motion from the last tracked frame to the current one, and its covariance.
  struct Bridge {
    Pose2 T_tracked_current;
    Eigen::Matrix3d covariance;
  };
  /// The bridge puts the robot back on the last tracked pose (within localization.min_anchor_offset_*): what features
  /// fixed to the camera say. Such a bridge is refused.
  bool backOnTheTrackedPose(const Bridge& bridge) const;
  /// The current frame's features fitted to the last tracked frame's, believed as a loop closure would be.
  std::optional<Bridge> bridgeByFeatures(const Keyframe& current) const;
  /// A bridge by features too weak alone, believed when it agrees with the lost segment's own estimate.
  std::optional<Bridge> corroboratedBridge(const Keyframe& current) const;
  /// The current image aligned with the last tracked frame's (started from as many usual steps as frames passed).
  std::optional<Bridge> bridgeByAlignment(const Keyframe& current, const AlignmentImage& alignment) const;
  /// The current frame's motion from the last tracked frame, searched among the motions the robot can have made
  /// at the loss frame (core/MotionSearch.hpp, odometry.bridge_search_*) followed by the lost segment's odometry.
  std::optional<Bridge> bridgeBySearch(const Keyframe& current) const;
  /// A searched (else spectrally registered) bridge once an earlier frame's, carried forward by the lost segment's
  /// odometry, agrees with it (that one's edge is added then); until then it waits in pending_search_ (cleared when a
  /// segment starts or joins the map).
  std::optional<Bridge> confirmedSearch(const Keyframe& current, const PreparedFrame& prepared);
  /// The current image registered with the last tracked frame's by their spectra (odometry.bridge_spectral_min_peak).
  /// Their motion is refined by aligning the two frames' images from it (alignedNear): the spectra measure the turn in
  /// half-degree bins.
  std::optional<Bridge> bridgeBySpectra(const Keyframe& current, const PreparedFrame& prepared) const;
  /// The motion from the image `before` to `turn_image` (both as turnBySpectra uses them) by their spectra, both less
  /// the mean of the recent images: believed with a clear phase correlation peak and a shift of the ground.
  std::optional<Bridge> motionBySpectra(const cv::Mat& before, const cv::Mat& turn_image, double turn_scale) const;
  /// The current segment joins the map (a relocalization): its frames count as measured, the graph is optimised.
  void joinMap(FrameResult& result);
  /// Lost segments that never joined the map are localized on it (after a segment joined it and was optimised in
  /// place); those found join it.
  void joinOrphanSegments(FrameResult& result);
  /// Localizations of lost frames on the map become loop edges, reported like loop closures.
  void addLocalizationEdges(const std::vector<LoopCandidate>& joined, FrameResult& result);
  /// The pixel warp (current image to previous) a ground motion T_prev_curr makes, and the ground motion of a warp;
  /// both through the calibrated camera, over a grid of the image's pixels.
  cv::Matx23d imageWarpOf(const Pose2& T_prev_curr) const;
  /// The same through each frame's own mount: the pixel warp the ground motion T_prev_curr makes between the two frames.
  cv::Matx23d imageWarpOf(const Pose2& T_prev_curr, const MountState& previous_mount, const MountState& current_mount) const;
  Pose2 groundMotionOf(const cv::Matx23d& W_previous_current) const;
  /// The same with each frame's pixels projected with its own mount (tilt and height).
  Pose2 groundMotionOf(const cv::Matx23d& W_previous_current, const MountState& previous_mount, const MountState& current_mount) const;
  /// The robust refinement alone from a transform known to within a few millimetres (see refineRigidTransform).
  RigidEstimate refineMatches(const std::vector<Match>& matches, const Keyframe& previous, const Keyframe& current,
                              const Pose2& initial) const;
  RigidEstimate fitMatches(const std::vector<Match>& matches, const Keyframe& previous, const Keyframe& current,
                           const FitSettings& settings, const std::optional<TransformPrior>& prior = std::nullopt) const;
  /// Matches split into still ones and the rest; when the rest fit a motion that moves the still ones, that fit.
  std::optional<RigidEstimate> fitWithoutStill(const StillSplit& split, const Keyframe& previous, const Keyframe& current) const;
  /// What the robot's steps make of a refused fit: the candidate they clearly point to, believed; failing that,
  /// the likeliest one, a guess for the assumed motion of a lost frame.
  struct StepsChoice {
    std::optional<RigidEstimate> believed;
    std::optional<Pose2> likeliest;
  };
  /// A fit refused as ambiguous or implausible, its rival transforms and the fits near the motions the robot
  /// can have made: the one the robot's motion clearly points to (OdometryChecks::repetition_*), or else the
  /// best supported one within repetition_max_doubts of its steps (MotionPrior::likeliest).
  StepsChoice fitByMotion(const RigidEstimate& fit, const std::vector<Match>& used, const Keyframe& previous,
                          const Keyframe& current) const;
  /// The robot's motion between consecutive frames lately (core/MotionPrior.hpp).
  Pose2 usualStep() const;
  /// The steps the robot may be making now: the usual one, or right after a turn on the spot two (see MotionPrior).
  std::vector<Pose2> usualSteps() const;
  /// An unconfirmed fit that spans a gap and that fewer than odometry.unconfirmed_gap_min_inlier_share of its
  /// matches agree with (a repeated floor fitted one repetition short of the gap).
  bool fewAgreeAcrossAGap(const OdometryEdge& edge, const Keyframe& previous, const Keyframe& current) const;
  /// On a repeated floor: the fit is far from every motion the robot can have made (repetition_margin doubts),
  /// or one of its rival repetitions is nearer to one.
  bool doubtedByTheSteps(const RigidEstimate& fit, const Keyframe& previous, const Keyframe& current) const;
  /// Where the robot can have gone between the two frames, from its usual steps (odometry.repetition_*).
  MotionPrior motionPrior(const Keyframe& previous, const Keyframe& current) const;
  /// The second look at a pair whose fit failed: the fit and the matches it used, or nothing.
  /// Matches without the still ones (outdoor.reject_still) and those in the artifact mask's cells: the robot's own
  /// shadow, dirt, bumper and glare.
  std::vector<Match> withoutRobotArtifacts(std::vector<Match> matches, const Keyframe& previous, const Keyframe& current) const;
  std::optional<std::pair<RigidEstimate, std::vector<Match>>> fitLowOverlap(const Keyframe& previous, const Keyframe& current) const;
  /// The current frame's roll, pitch and height from the odometry's inliers; its points re-projected and the
  /// odometry fitted again with them. Leaves everything as it was when the estimate fails.
  void estimateMountOf(const Keyframe& previous, Keyframe& current, OdometryEdge& odometry, const TrackingImage& tracking,
                       FrameResult& result);
  /// The previous frame's pairs with its side tracked from the current keypoints by the images (outdoor.track_points):
  /// the observation the mount is estimated from, or nothing when too few points track.
  std::optional<MountObservation> trackedObservation(const Keyframe& previous, const Keyframe& current, const std::vector<Match>& pairs,
                                                     const Pose2& T_previous_current, const TrackingImage& tracking) const;
  /// A frame the mount is estimated against: the matches (current = query) and motion to it.
  struct MountReference {
    const Keyframe* keyframe = nullptr;
    std::vector<Match> matches;
    Pose2 T_reference_current;
  };
  /// The oldest recent frame of this segment, other than the previous one, within the mount estimation's
  /// baseline of the current pose (empty when there is none or it does not match).
  std::optional<MountReference> farReference(const Keyframe& current, const OdometryEdge& odometry) const;
  /// The matches whose points T_reference_current brings within the mount estimate's pair radius.
  std::vector<Match> mountPairs(const std::vector<Match>& matches, const GroundFeatures& current, const GroundFeatures& reference,
                                const Pose2& T_reference_current) const;
  MountEstimationSettings mountSettings() const;
  bool loopsKeepRays() const { return config_.loop_closure.refine_by_tracked_points || config_.loop_closure.remeasure_at_end; }
  bool mountFromLoops() const {
    return config_.outdoor.estimate_mount && config_.outdoor.smooth_mount && config_.outdoor.mount_from_loops;
  }
  /// The factor of a frame's estimate against one of its references (divided by outdoor.variance_inflation, as
  /// every factor is) into mount_factors_.
  void keepMountFactor(const MountEstimate& estimate, const std::vector<int>& frames, bool chooses_priors);
  /// An accepted loop closure is a pair of views like any other, with a baseline of minutes instead of a
  /// frame: its factor ties the two frames' mounts across the run (the place must have kept its rays).
  void addLoopMountFactor(const LoopCandidate& loop, const Keyframe& current);
  /// The motion assumed for a frame odometry could not measure: the previous one, turned by `turn` when measured,
  /// or the refused fit's likeliest candidate (fallback.likeliest_motion).
  OdometryEdge fallbackOdometry(OdometryEdge failed, std::optional<double> turn = std::nullopt,
                                std::optional<Pose2> likeliest = std::nullopt) const;
  /// The turn of a fit refused for its rivals or its speed, when it still measures one (fallback.turn_min_inliers).
  std::optional<double> measuredTurn(const RigidEstimate& refused) const;
  /// A turn of the robot over a turn of its images (-1: the camera sees the ground mirrored).
  static double imageTurnSign(const CameraModel& camera, const CameraIntrinsics& intrinsics);
  /// A failed frame's whole motion from the images' spectra, where they register the two images on a floor that does
  /// not repeat (FallbackSettings::motion_by_spectra); whether it was.
  bool motionBySpectraAssumed(OdometryEdge& failed, const Keyframe& current, const PreparedFrame& prepared) const;
  /// A failed frame's turn from the images' spectra, where they clearly tell it (FallbackSettings::turn_*).
  void turnBySpectra(OdometryEdge& failed, const cv::Mat& turn_image) const;
  /// The mean of the recent turn images, which turnBySpectra takes away: what stays in the image.
  void keepTurnImage(cv::Mat turn_image);
  /// Two images show about as much contrast as each other (a blank or covered one shows no motion).
  static bool comparableContrast(const cv::Mat& a, const cv::Mat& b);
  /// False when the motion's translation is far from the last good motion's, scaled to the time between frames
  /// (config odometry.max_velocity_change_*).
  bool plausibleMotion(const Pose2& T_prev_curr, double previous_time, double current_time) const;
  /// How many frames' worth of travel a motion spans: its time over the last good motion's and its length over
  /// the median of the last good ones', whichever is more (at least 1; a failed motion: infinite). Frames dropped
  /// without a trace in the timestamps still show in the length; the mount rocked over all of them.
  double rockingSteps(const OdometryEdge& odometry, double previous_time, double current_time) const;
  /// The fit's own covariance keeps its motion within the `ok` tolerance (OdometryChecks::ok_sigmas), and a fit at rest
  /// comes after the robot was seen moving (seen_moving_).
  bool vouchedFor(const OdometryEdge& odometry, const Keyframe& current) const;
  /// On a floor whose images repeat (odometry.floor_repeat_*): a motion not vouched for (not `ok`) whose inliers
  /// fell below odometry.repeated_floor_unsure_inlier_share of the recent frames' median may be one repetition off
  /// (frames dropped where the fit found the tile before). Keeps the frame's inliers among the recent ones.
  bool mayBeARepetitionOff(const FrameResult& result);
  /// Every match the fit used stays where it was in the image (within movedDistanceM on the ground).
  bool atRest(const Pose2& fitted, const std::vector<Match>& used, const Keyframe& current) const;
  /// Every keypoint of the frame stays where it was in the image under the motion (within movedDistanceM on the ground).
  bool keypointsStayPut(const Pose2& T_prev_curr, const Keyframe& current) const;
  /// How far a fit must move a still match on the ground for the robot to have moved (outdoor.moved_factor still
  /// radii): less, and the match may be ground at rest as well as the robot's own artifact.
  double movedDistanceM() const { return config_.outdoor.moved_factor * config_.outdoor.still_radius_px * ground_sample_m_; }
  /// True when the turn makes the tilt's lever arm longer than odometry.sharp_turn_lever_m (OdometryChecks).
  bool sharpTurn(const Pose2& T_prev_curr) const;
  /// True when a motion spans at least odometry.gap_min_steps frames' travel (rockingSteps).
  bool spansGap(double steps) const;
  void addToGraph(const OdometryEdge& odometry);
  /// What of the current frame goes to loop closure and the map: its features outside artifact cells and
  /// not among this frame's still matches. The previous frame's still features leave its pending place too.
  Keyframe groundOf(const Keyframe& current, const std::vector<Match>& still);
  /// Features of `current` at the place of a like feature of `previous` in the image although the motion
  /// moved them (config outdoor.still_max_hamming): the robot's own shadow edge, dirt, bumper, glare.
  std::vector<Match> stillFeatures(const Keyframe& previous, const Keyframe& current, const Pose2& T_prev_curr) const;
  /// Tracking is lost: a new segment starts, tied to the last one by an edge with almost no information.
  void startSegment(const OdometryEdge& failed);
  /// Tracking is lost for the first time (or again right after) before the map holds
  /// odometry.restart_map_below_frames frames: the map starts again at this frame, and the frames before it
  /// are left out of it (not measured, never places or map keyframes).
  void restartMap(const OdometryEdge& failed);
  /// A pose for a frame whose motion is unknown (the failed fit's fallback), tied by an edge with almost no
  /// information; its index.
  int addUnmeasuredMotion(const OdometryEdge& failed);
  /// While lost: global localization; once it is accepted, the segment joins the map and the graph is optimised.
  void relocalize(const Keyframe& current, FrameResult& result);
  void closeLoops(const Keyframe& current, const TrackingImage& tracking, FrameResult& result);
  /// The rays of a loop's pairs (the place's, frame a, and the current frame's, b) and the graph edge they measure.
  struct LoopRays {
    size_t edge = 0;
    int frame_a = 0, frame_b = 0;
    std::vector<Eigen::Vector2d> a_rays, b_rays;
  };
  /// An accepted loop's pairs: its keypoint pairs tracked into the place's image when they track
  /// (loop_closure.refine_by_tracked_points; the loop then refitted on them), else its keypoints' guided pairs.
  std::optional<LoopRays> measureLoopPairs(LoopCandidate& loop, const Keyframe& current, const TrackingImage& tracking) const;
  /// A loop candidate's keypoint pairs matched around T_a_b (outdoor.reference_match_radius_m).
  LoopRays guidedLoopPairs(const LoopCandidate& loop, const Keyframe& current, const GroundFeatures& reference, const Pose2& T_a_b) const;
  /// Current keypoints paired with where T_a_b puts them in the place's image (for rescueLoop: the keypoints'
  /// own matches are too few there); at most kRescuePairs, those landing inside the image.
  LoopRays predictedLoopPairs(const LoopCandidate& loop, const Keyframe& current, const Pose2& T_a_b) const;
  static constexpr size_t kRescuePairs = 300;
  /// Keypoint pairs' current keypoints tracked into the place's image (loop_closure.refine_by_tracked_points):
  /// the tracked pairs, or empty when too few track.
  std::optional<LoopRays> trackLoopPairs(const LoopRays& keypoints, const TrackingImage& tracking) const;
  /// A candidate that failed gate 3 with a coarse transform (loop_closure.rescue_min_inliers), measured by tracked
  /// points: accepted, with its tracked pairs, when they pass gate 3 and agree with the coarse transform.
  std::optional<LoopRays> rescueLoop(LoopCandidate& loop, const Keyframe& current, const TrackingImage& tracking) const;
  /// How far (radians) a rescued loop's tracked fit may turn from the keypoints' coarse transform.
  static constexpr double kRescueAgreementRad = 1.0 * M_PI / 180.0;
  /// The fit of a loop's pairs projected through the given mounts, its covariance including the mounts' tilt
  /// (mountCovariance); empty when the fit fails.
  std::optional<RigidEstimate> fitLoopRays(const LoopRays& pairs, const MountState& a_mount, const MountState& b_mount,
                                           const Pose2& T_guess) const;
  /// At the end, once the mounts are smoothed: every loop's edge turned and shifted by what its pairs' fit changes
  /// from the mounts used to its frames' final mounts (loop_closure.remeasure_at_end); true when an edge changed
  /// (finish() then optimises the graph again).
  bool remeasureLoops();
  /// Rays (normalised image coordinates) projected to the ground through the given mount.
  GroundFeatures projectRays(const std::vector<Eigen::Vector2d>& rays, const MountState& mount) const;
  /// Pairs a, b projected through the given mounts and fitted (no mount covariance).
  RigidEstimate fitRays(const LoopRays& pairs, const MountState& a_mount, const MountState& b_mount, const Pose2& T_guess) const;
  /// A sample of an odometry edge's inlier pairs, kept for remeasureOdometry (outdoor.remeasure_odometry).
  void keepOdometryPairs(const OdometryEdge& odometry, const Keyframe& previous, const Keyframe& current);
  /// At the end, once the mounts are smoothed: every odometry edge turned by what its pairs' fit turns from the mounts
  /// used to the final ones, beyond the poses' corrections; true when an edge changed.
  bool remeasureOdometry();
  /// Pairs kept per odometry edge: the change of their fit, not the fit itself, is used, and their noise cancels in it.
  static constexpr size_t kRemeasuredPairs = 64;
  std::vector<LoopRays> odometry_rays_;       ///< per odometry edge, for remeasureOdometry
  std::map<int, Pose2> remeasured_odometry_;  ///< by frame: each step as remeasureOdometry made it, for finalOdometry
  /// Keeps the frame's tracking image while it may still become a place, and a place's for good.
  void keepPlaceTracking(int frame, const TrackingImage& tracking);
  /// The covariance a pair of views' transform gets from their frames' tilt estimates (loop_closure.tilt_sigma_deg).
  Eigen::Matrix3d mountCovariance(const Pose2& T_a_b, const GroundFeatures& a_points, const MountState& a_mount,
                                  const GroundFeatures& b_points, const MountState& b_mount) const;
  /// The pixel a keypoint's normalised ray came from.
  std::optional<cv::Point2d> pixelOfRay(const Eigen::Vector2d& ray) const;
  /// With a prior map, every localization.every_frames frames: a loop closure to the prior map's keyframes.
  void closeLoopsOnPriorMap(const Keyframe& current, FrameResult& result);
  /// A candidate as reported: frames of this session count from 0, the prior map's keyframes are negative.
  LoopCandidate reported(LoopCandidate candidate) const;
  void optimiseIfDue(FrameResult& result, bool at_end);

  Config config_;
  FitSettings odometry_fitting_;  ///< the odometry settings, rivals measured (see odometry_checks)
  FramePreparer preparer_;
  DescriptorMatcher matcher_;
  CameraModel camera_;
  Eigen::Isometry3d calibrated_mount_;
  double ground_sample_m_ = 0.0;   ///< metres per pixel at the image centre
  ArtifactMask artifact_mask_;
  double mount_baseline_m_ = 0.0;
  double mount_pair_radius_m_ = 0.0;
  /// How much the mount really rocks and bounces, against how noisy one frame's estimate is: running means
  /// of the estimates' squared departure from the calibrated mount and of their variance. A rigid mount's
  /// estimates are all noise, and are then shrunk to the calibrated mount.
  struct Spread {
    double square_mean = 0.0, variance_mean = 0.0;
    /// Adds one estimate; returns the share of the departure to keep.
    double keep(double square, double variance, int count);
  };
  /// Images that refine the odometry's heading, of one kind (the alignment's, or the contrast-normalised ones used
  /// where the robot's own artifacts are seen), and how far their heading has been from the keypoints' so far.
  struct HeadingImages {
    ImageAlignmentSettings settings;
    /// How far the images' heading is from the keypoints' (running mean of the squared difference) against the
    /// keypoint fits' own heading variance: what is left over is the images' variance.
    Spread spread;
    int count = 0;
    /// The combined heading's variance replaces the fit's. Not where the robot's own artifacts are seen: what is
    /// left of the shadow's edge, which turns with the heading, errs alike on every frame of a turn, and a chain
    /// that claimed the combination's variance would outweigh the loop closures that correct it (measured on the
    /// outdoor floors, seeds 11 and 23, before refineAlignment left out the previous pixels that land on the current
    /// image's blanked ones: SLAM heading error x0.85 and x1.03 of the keypoints' alone with the fit's variance kept,
    /// x1.02 and x1.28 with the combination's).
    bool narrows_variance = true;
    /// While the variance is learnt (the run's first kLearntHeadings frames) the images' heading is not used yet:
    /// each frame's difference, kept to refine its edge once the variance is known (refineEarlyHeadings).
    struct EarlyDifference {
      int frame = 0;
      double difference_rad = 0.0;
      Eigen::Vector2d pivot = Eigen::Vector2d::Zero();  ///< the fit's matches' centroid in that frame
    };
    std::vector<EarlyDifference> early;
  };
  /// An odometry edge as the keypoints fitted it, kept while the heading images learn their variance.
  struct EarlyFit {
    size_t edge = 0;  ///< its index in graph_
    Pose2 T_prev_curr;
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  };
  /// The edges of the frames `source` measured while it learnt its variance, refined by its images now that the
  /// variance is known (when it is not less precise than the keypoints), and the frames after them moved along.
  /// Without this the run's first frames keep the keypoints' heading alone: measured on the standard carpet
  /// lawnmower, 0.16 degrees of heading drift over its first 10 frames, which every later pose inherits.
  void refineEarlyHeadings(HeadingImages& source);
  std::map<int, EarlyFit> early_fits_;  ///< by frame, for refineEarlyHeadings
  std::map<int, Pose2> refined_early_odometry_;  ///< by frame: the edges refineEarlyHeadings made, for finalOdometry
  /// Adds one difference of the images' heading from a fit's to `source`; the images' heading variance learnt so far
  /// (what the squared differences leave beyond the fits' own variance, odometry.align_heading_sigma_deg at least),
  /// nothing while fewer than 10 differences are known.
  std::optional<double> imageHeadingVariance(HeadingImages& source, double difference, double fit_variance) const;
  /// True once `source`'s images are known to be less precise in heading than the keypoints (then not used).
  bool lessPreciseThanKeypoints(const HeadingImages& source) const;
  /// The images' heading variance a spread says (at least odometry.align_heading_sigma_deg squared).
  double learntVariance(const Spread& spread) const;
  /// True when the finer heading images have measured the turn more precisely than the alignment's reduced images
  /// (and than the keypoints): fine_headings_ is then used where nothing stays still.
  bool finerHeadingImagesBetter() const;
  /// Headings are learnt from this many frames before they are used.
  static constexpr int kLearntHeadings = 10;
  /// Where one kind of heading image is in use, the other is measured (its precision learnt) on every this many frames.
  static constexpr int kFineHeadingCheckFrames = 20;
  /// The finer heading images are used where their learnt variance is at most this share of the reduced images'.
  static constexpr double kFinerHeadingVarianceShare = 0.5;
  Spread tilt_spread_, height_spread_;
  HeadingImages plain_headings_;     ///< the alignment's images, where nothing stays still in them
  HeadingImages artifact_headings_;  ///< contrast-normalised images, where the robot's own artifacts are seen
  /// The same contrast-normalised images where nothing stays still but the alignment's reduced images blur the floor
  /// away (a fine texture such as carpet: their heading less precise than the keypoints').
  HeadingImages fine_headings_;
  int fine_check_count_ = 0;  ///< frames where nothing stayed still, for kFineHeadingCheckFrames
  int mount_estimates_ = 0;
  std::vector<FrameMountFactor> mount_factors_;  ///< every mount estimate's factor (graph frames)
  std::vector<MountState> used_mounts_;        ///< per graph frame: the mount its points were projected with
  /// Per graph frame: how many frames' worth of rocking lie since the previous one (smoothMounts' steps).
  std::vector<double> rocking_steps_;
  std::vector<MountState> final_mounts_;       ///< per graph frame, from smoothMounts at finish()
  std::optional<MountRocking> mount_rocking_;

  std::vector<Pose2> mount_corrections_;       ///< per graph frame: robot pose under final_mounts_ = graph pose * this
  /// The whole run's mount states (core/MountSmoother) and each frame's pose correction for them.
  void smoothMount();
  std::deque<Keyframe> recent_;  ///< tracked frames of the current segment, newest last (mount references)
  std::optional<LoopCloser> loop_closer_;
  PoseGraph graph_;
  std::optional<Keyframe> previous_;
  AlignmentImage previous_alignment_;  ///< the previous image as the alignment uses it (odometry.align_images)
  AlignmentImage previous_heading_;    ///< the previous image as the heading refinement uses it where artifacts are seen
  /// The mean of the recent heading images (over fallback.turn_background_frames, as turn_background_): what stays in
  /// the image. Taken away from both images once this many were seen.
  cv::Mat heading_background_;
  int heading_images_seen_ = 0;
  static constexpr int kHeadingBackgroundImages = 3;
  /// heading_background_ with `image` in it.
  void keepHeadingImage(const AlignmentImage& image);
  cv::Mat previous_turn_image_;  ///< the previous image as turnBySpectra uses it (CV_32F)
  cv::Mat turn_background_;      ///< the mean of the recent turn images (FallbackSettings::turn_background_frames)
  int turn_images_seen_ = 0;
  double image_turn_sign_ = 1.0;  ///< a turn of the robot over a turn of the image (-1: the camera sees the ground mirrored)
  TrackingImage previous_tracking_;    ///< the previous image as the point tracker uses it (outdoor.track_points)
  std::map<int, TrackingImage> place_tracking_;  ///< graph frame -> its tracking image, for places and frames still pending
  std::deque<int> pending_place_tracking_;       ///< frames whose image is kept until it is known whether they became places
  std::vector<LoopRays> loop_rays_;              ///< every loop closed during the run, for remeasureLoops
  cv::Mat tracked_turn_image_;         ///< the last tracked frame's image as bridgeBySpectra uses it
  AlignmentImage tracked_alignment_;   ///< the last tracked frame's image, keyframe, graph index and time (bridgeLoss)
  AlignmentImage tracked_heading_;     ///< its heading image (bridgeBySpectra)
  std::optional<Keyframe> tracked_keyframe_;  ///< its features as projected with its mount (bridgeByFeatures)
  int tracked_frame_ = -1;
  double tracked_time_ = 0.0;
  /// The tracked frame's segment and that segment's first frame: a loss inside a lost segment is bridged to the
  /// segment's own frames, and the new segment joins it (not the map).
  int tracked_segment_ = kMapSegment;
  int tracked_segment_start_ = 0;
  ImageAlignmentSettings alignment_settings_;
  PointTrackingSettings point_tracking_;  ///< outdoor.track_points
  std::optional<OdometryEdge> last_good_odometry_;
  /// Some odometry fit of this run moved its matches (not atRest). Until then a fit at rest cannot be told from the
  /// robot's own shadow edge, lens dirt and bumper, which stay still whether or not it moves: such a fit is not `ok`.
  bool seen_moving_ = false;
  /// The time between the two frames of last_good_odometry_; 0 after a failed frame (no speed to judge by).
  double last_good_odometry_seconds_ = 0.0;
  static constexpr size_t kRecentSteps = 5;
  /// A floor is taken to repeat for this many frames after an odometry fit had a rival repetition.
  static constexpr int kRepeatedFloorFrames = 20;
  int last_rival_frame_ = -1;  ///< the last frame whose odometry fit had a rival
  /// The floor repeats: one of the last kRepeatedFloorFrames odometry fits up to `frame` had a rival repetition.
  bool repeatedFloor(int frame) const { return withinRepeatedFloorFrames(last_rival_frame_, frame); }
  int last_repetition_frame_ = -1;  ///< the last frame whose odometry fit had a rival with a fit's inliers
  /// For bridges: one of the last kRepeatedFloorFrames fits up to `frame` had a rival that showsARepetition.
  bool repetitionShown(int frame) const { return withinRepeatedFloorFrames(last_repetition_frame_, frame); }
  /// `frame` lies at most kRepeatedFloorFrames after `last` (-1: never).
  static bool withinRepeatedFloorFrames(int last, int frame) { return last >= 0 && frame - last <= kRepeatedFloorFrames; }
  /// The images say the floor repeats (odometry.floor_repeat_*), for the rest of the run: a loss there for a motion
  /// unlike the robot's is not bridged (startSegment).
  bool floor_looks_repeated_ = false;
  int repeated_checks_in_a_row_ = 0;   ///< the last checks that reached the strength
  /// Every odometry.floor_repeat_check_frames frames of the session: the image's repetition strength, until the
  /// floor repeats.
  void noteRepetition(int session_frame, const cv::Mat& turn_image);
  /// Tracking was lost in a way bridgeableLoss allows (too little evidence, the robot's speed, a weak floor's rival) on a
  /// floor that does not repeat: bridgeLoss may join it.
  bool bridgeable_loss_ = false;
  /// A searched bridge waiting for a later frame's to agree with it (confirmedSearch).
  struct PendingBridge {
    int frame = -1;
    Bridge bridge;
  };
  std::optional<PendingBridge> pending_search_;
  std::deque<int> recent_inliers_;  ///< the last 2 kRecentSteps frames' inliers (those with a fit)
  std::deque<Pose2> recent_steps_;  ///< the last kRecentSteps good motions, a gap's shared among its steps
  /// Good motions in a row that each spanned a gap (their whole length); odometry.speed_change_frames of them
  /// replace recent_steps_: the usual step changed.
  std::deque<Pose2> long_steps_;
  size_t steps_since_turn_ = 0;     ///< good motions since the last sharp turn (recent_steps_ before it point elsewhere)
  std::optional<std::pair<Pose2, double>> before_turn_;  ///< the usual step before the last sharp turn, and its turn
  std::vector<double> timestamps_;
  std::vector<bool> measured_;  ///< per frame: its pose came from a measurement, not a fallback
  std::vector<LoopCandidate> candidates_;
  std::function<void(const LoopCandidate&)> candidate_observer_;
  bool keep_candidates_ = true;
  void report(const LoopCandidate& candidate);
  int unoptimised_loops_ = 0;
  bool full_optimisation_due_ = false;  ///< a loop closure corrected the estimate by more than graph.full_optimisation_correction_m
  bool window_solved_ = false;          ///< a windowed optimisation ran since the last full one
  int last_optimised_frame_ = -1000000;
  bool optimise_now_ = false;  ///< a relocalization joined a segment: optimise the whole graph at once
  int segment_ = kMapSegment;  ///< the current tracking segment
  int segments_started_ = kMapSegment;  ///< the last segment number given out
  bool orphans_due_ = false;  ///< a segment joined the map: earlier lost segments are to be localized on it
  bool lost_ = false;          ///< tracking was lost and the current segment is not yet joined to the map
  int lost_since_ = 0;         ///< first frame of the current segment
  int map_start_ = 0;          ///< the map's first frame (later than 0 when tracking was lost at once)
  /// The run's first frames' images, while the map may still start again (odometry_checks.restart_map_below_frames):
  /// where it did, the motions given up there are measured again from them once the alignment knows the usual step
  /// and the mean of the heading images, and the frames join the map (pipeline/SlamGivenUpFrames.cpp).
  struct EarlyImages {
    AlignmentImage reduced, heading;
  };
  std::vector<EarlyImages> early_images_;
  bool given_up_frames_measured_ = false;
  /// A motion's graph edge with less information in heading than this was not measured (informationFreeEdge).
  static constexpr double kLeastMeasuredInformation = 1.0;
  void keepEarlyImages(int frame, const PreparedFrame& prepared);
  /// Once the map can no longer start again: the given-up motions from map_start_ back, each aligned as odometry
  /// aligns a frame from the usual steps, until one is not believed; each measured joins its frame to the map.
  void remeasureGivenUpFrames(int frame);
  std::optional<OdometryEdge> alignedGivenUpMotion(int from, int to) const;
  /// The odometry edge (not a loop) from `from` to `to`, if any.
  std::optional<size_t> odometryEdgeBetween(int from, int to) const;
  bool ever_lost_ = false;     ///< tracking was lost before (the map starts again only at the run's first loss)
  int prior_frames_ = 0;       ///< graph poses 0..prior_frames_-1 are a prior map's keyframes, held fixed
  int last_prior_attempt_ = -1000000;  ///< frame of the last localization on the prior map
};

}  // namespace groundslam
