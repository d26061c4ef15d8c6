#pragma once
// The pipeline's configuration: one plain struct per component, defaults in code. Every field is
// listed once in visitConfigFields(), which the YAML reader and writer both walk, so a key cannot be
// readable but not written, or written but not validated. What only the programs reading files need (the
// vocabulary's path, a dataset's map scale) is not here but in io/ConfigYaml.hpp's InputSettings.

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/PoseGraph.hpp"
#include "groundslam/core/RigidFit.hpp"
#include "groundslam/core/StillFeatures.hpp"
#include "groundslam/localization/GlobalLocalizer.hpp"
#include "groundslam/pipeline/LoopClosure.hpp"

namespace groundslam {

struct CameraConfig {
  int image_width = 0;                      ///< pixels (required)
  int image_height = 0;                     ///< pixels (required)
  double fx = 0.0, fy = 0.0;                ///< focal lengths, pixels (required)
  double cx = 0.0, cy = 0.0;                ///< principal point, pixels (required)
  std::array<double, 5> distortion{};       ///< OpenCV k1 k2 p1 p2 k3 (required); equidistant: k1 k2 k3 k4 0
  DistortionModel distortion_model = DistortionModel::radtan;  ///< radtan (OpenCV, ROS plumb_bob) | equidistant (fisheye)
  double mounting_height_m = 0.25;          ///< used when T_robot_camera is absent (required)
  std::optional<std::array<double, 16>> T_robot_camera;  ///< row-major 4x4, overrides the default mount
};

/// What odometry assumes when a frame cannot be matched (e.g. a textureless image): the previous
/// motion again, with this much uncertainty added, so loop closures can still correct it.
struct FallbackSettings {
  double sigma_m = 0.01;     ///< standard deviation added to x and y, metres
  double sigma_rad = 0.05;   ///< standard deviation added to the heading, radians
  /// A fit refused for its rival repetitions or its speed (a repeated floor, frames dropped without a trace), not
  /// for too little evidence, still measures the turn when it has this many inliers: the assumed motion turns by
  /// it (0: by the previous motion's turn).
  int turn_min_inliers = 25;
  /// Such a fit's likeliest motion replaces the assumed one, turn and translation: of the fit, its rivals and the
  /// fits near each motion the robot can have made, the one with the most inliers within repetition_max_doubts of
  /// the robot's steps, those whose turn the steps explain before one step with a sudden turn (frames dropped
  /// without a trace: several steps on; MotionPrior::likeliest). The frame stays lost.
  bool likeliest_motion = true;
  /// Any other failed frame takes its turn from the images' spectra (core/SpectralTurn.hpp), the mean of the last
  /// `turn_background_frames` images taken away from both (what stays in the image: the robot's bumper, dirt on the
  /// lens). Images reduced to this width or less, pixels (0: off, the previous motion's turn).
  int turn_image_width_px = 320;
  double turn_min_peak_ratio = 1.2;  ///< the spectra's best turn must correlate this many times the best one 5 degrees away
  /// Known only up to half a turn: the one whose undoing leaves the images matching by a translation this many times
  /// better (their phase correlation's peak); failing that, the one nearer the previous motion's turn by at least
  /// turn_min_margin_deg.
  double turn_half_turn_ratio = 2.0;
  double turn_min_margin_deg = 20.0;
  int turn_background_frames = 30;
  /// Before its turn alone, such a frame takes its whole motion from the spectra where they register the two images,
  /// as a bridge does (a clear phase correlation peak at a shift of the ground, odometry.bridge_spectral_min_peak), on
  /// a floor that does not repeat: a lost segment that is never found again lies where the robot went (measured on
  /// faint floors: a quarter turn with frames dropped, 50 mm and 99 degrees, whose turn alone was not clear enough,
  /// left the rest of the run 99 degrees off where the registration was 3 mm and 0.4 degrees off). The frame stays lost.
  bool motion_by_spectra = true;
};

/// How measurements become graph edges and when the graph is optimised.
struct GraphConfig {
  double min_sigma_m = 0.0005;     ///< floor on an edge's position standard deviation (unmodelled errors: a rocking mount)
  double min_sigma_rad = 0.0001;   ///< floor on an edge's heading standard deviation
  int optimise_every_frames = 10;  ///< after a loop closure, optimise at most this often (and once at the end)
  /// Optimise only the last this many poses, the earlier ones held fixed (0: the whole graph every time).
  /// The whole graph is optimised at the end, and when a loop closure corrects the estimate by more than
  /// full_optimisation_correction_m (drift built up over a long path is spread over all of it).
  int window_frames = 100;
  double full_optimisation_correction_m = 0.01;
  PoseGraphSettings solver;
};

/// Checks on an odometry fit beyond the fit's own success.
struct OdometryChecks {
  double max_ambiguity = 0.5;  ///< a rival transform with this share of the fit's inliers makes the motion unknown
  /// A motion whose translation differs from the last good one's, scaled to the time between the frames, by more
  /// than max_velocity_change_m + max_velocity_change_fraction * that prediction is not believed (a repeated
  /// floor matched one repetition over after a gap). Rotation is free: sharp turns are allowed.
  double max_velocity_change_m = 0.02;
  double max_velocity_change_fraction = 0.5;
  /// A fit that at least this share of its matches agrees with is believed whatever the robot's speed: frames
  /// dropped without a trace in the timestamps make a true motion look too fast, and a repeated floor spreads
  /// its matches over the repetitions, so its wrong fits never reach it. Above 1: never.
  double decisive_inlier_share = 0.8;
  /// When the fit has too little evidence (e.g. dropped frames leave 40% overlap: too few matches survive the
  /// ratio test, or those that do crowd into a corner), the pair is matched again with this looser ratio test and the fit is
  /// kept if no rival transform has more than low_overlap_max_ambiguity of its inliers; the frame says
  /// `low_overlap`. Its speed is not judged (the gap's length is unknown). At or below matching.ratio: off.
  double low_overlap_ratio = 0.8;
  double low_overlap_max_ambiguity = 0.1;
  /// Only where the overlap fell: the ratio test kept at most this share of the matches of the last good motion
  /// (on a floor that gives few matches everywhere, a looser test only adds look-alikes).
  double low_overlap_max_match_share = 0.5;
  /// Standard deviations added to a low-overlap motion's covariance: its matches crowd into the small shared
  /// area, and over a gap a rocking mount's tilt differs between the frames (1 degree at 25 cm: 4 mm).
  double low_overlap_sigma_m = 0.005;
  double low_overlap_sigma_rad = 0.005;
  /// Not in the paper: where the fit still has too little evidence (too few matches or inliers, or all of them in
  /// a line: a smooth floor, mortar lines) and the floor does not repeat, the motion is found by aligning the two
  /// images themselves (core/ImageAlignment.hpp, reduced to align_width_px), started from one and from up to
  /// repetition_max_steps of the robot's usual steps. It is
  /// believed when the alignment's correlation reaches align_min_correlation, it explains the images
  /// align_rest_ratio times better than rest does and than any start that ended elsewhere does (their
  /// decorrelation there over that after the warp: what is left of a floor under a glare and a shadow may say only
  /// "no motion"; on tiles a start one tile over ends as well explained), starts a few pixels around it come back within
  /// align_max_spread_m and its speed is plausible; the frame says `aligned`, and align_sigma_* are added
  /// to the edge's standard deviations. false: off.
  bool align_images = true;
  int align_width_px = 160;
  /// The images' background light is removed with a Gaussian blur this share of the reduced width; with
  /// align_normalise_contrast each pixel is also divided by the contrast around it (over the same blur), so that the
  /// ground under the robot's shadow counts as much as the ground in the light and a lamp's glare adds nothing.
  double align_highpass_fraction = 0.08;
  bool align_normalise_contrast = false;
  double align_min_correlation = 0.7;
  /// Odometry aligns the contrast-normalised heading images (outdoor.heading_image_width_px) first: what stays still
  /// in the image pulls them least. Finer and noisier than the reduced images, they correlate less: their alignment
  /// is believed from this correlation on, the other conditions as above.
  double align_heading_images_min_correlation = 0.6;
  double align_rest_ratio = 2.0;
  double align_max_spread_m = 0.002;
  double align_sigma_m = 0.005;
  double align_sigma_rad = 0.005;
  /// An alignment that moves the robot less than this share of its usual step (before any step was measured: less
  /// than a still feature's radius times outdoor.moved_factor) is not believed, unless it turns sharply on the spot:
  /// the robot's shadow and glare, and a smooth floor's sameness, align best near rest. 0: any.
  double align_min_step_share = 0.5;
  /// A fit that leaves every match in place (the robot at rest) is refuted when the two images' spectra, less the mean
  /// of the recent images, register with a clear peak (bridge_spectral_min_peak) at a shift of the ground: on a floor
  /// too faint to match, the robot's shadow edge, lens dirt and bumper are all that match, and they say "at rest"
  /// while it drives. The images are then aligned from the spectra's motion (`aligned`), else the frame's motion is
  /// not known (`fallback_still`, or `lost_still` with loop closure). false: rest is never checked.
  bool rest_check_by_spectra = true;
  /// A fit refused for too little evidence (too few matches or inliers, degenerate) on a floor that does not repeat is
  /// measured again from the images' spectra, less the mean of the recent images. Where they show a motion spanning
  /// frames dropped (at least 1.5 of the robot's usual steps long) the features are matched only near where that
  /// motion puts them (bridge_search_radius_m), and the fit is kept (`low_overlap`) when it has no rival and stays
  /// within align_sigma_m and 1 degree of it; else, and for any other motion, the images are aligned from that motion
  /// (`aligned`), kept as closely. Frames dropped without a trace leave the images overlapping by less than half: too
  /// few features match among all of them. false: such a fit is a loss.
  bool gap_by_spectra = true;
  /// A fit with fewer inliers than this is checked by aligning the images from its motion: an alignment believed
  /// as above that ends more than align_check_m or align_check_rad away replaces it (the frame says `aligned`)
  /// when the fit's matches support it nearly as well: at least align_check_support times as many of them lie
  /// within align_check_radius_m of where it puts them as of where the fit does. On weak floors (mortar lines, a
  /// blurred photo) a few dozen keypoints often sit on edges that place them well only across the edge, and such
  /// a fit can be a degree off; on a fine texture the reduced images blur, the matches refute a wrong alignment.
  /// 0: never checked.
  int align_check_below_inliers = 60;
  double align_check_m = 0.002;
  double align_check_rad = 0.005;
  double align_check_radius_m = 0.001;
  double align_check_support = 0.75;
  /// A checked fit with fewer inliers than this that the images neither confirm (within align_check_m / _rad)
  /// nor replace stands, less certain: the frame says `unconfirmed` and align_sigma_* are added to its edge's
  /// standard deviations (a fit of a dozen or two keypoints on a weak floor is a degree off one time in ten).
  /// 0: never.
  int align_confirm_below_inliers = 30;
  /// Such an unconfirmed fit that spans a gap (gap_min_steps) and that fewer than this share of its matches agree
  /// with is refused as ambiguous: on a repeated floor (tiles) a gap dropped without a trace fits one repetition
  /// short as readily as right (measured on tiles: 8-11% of the matches, two such fits a tile off for one right;
  /// a true gap's fit on a floor that does not repeat has 62-100%). The frame is lost, not bridged (a bridge would
  /// meet the same repetitions). 0: never.
  double unconfirmed_gap_min_inlier_share = 0.3;
  /// Every measured motion (not a low-overlap, aligned or lost one) has its heading refined by aligning the images
  /// from it (where something stays still in them, images of their own: outdoor.heading_image_width_px): the
  /// keypoints' heading and the images' are combined by
  /// their variances, the images' learnt over the run (the squared differences less the fits' own variance) and at
  /// least this standard deviation (degrees; measured 0.007-0.011 at 160 pixels wide against the keypoints'
  /// 0.02-0.04). Images less precise than the keypoints are not used. An alignment that does not converge,
  /// correlates less than align_min_correlation or ends farther than align_check_m / align_check_rad from the fit
  /// leaves it as it was. 0: off.
  double align_heading_sigma_deg = 0.01;
  /// Where nothing stays still, the finer contrast-normalised heading images (outdoor.heading_image_width_px) refine
  /// the heading instead of the alignment's reduced images once their learnt variance is at most half the reduced
  /// images' (a fine floor, carpet, that the reduced images blur away); the images not in use are measured on every
  /// 20th frame, so that a change of floor is seen. False: the reduced images only.
  bool finer_heading_images = true;
  /// A turn moves the ground by the camera's tilt error too: a tilt off by delta shifts every ground point by
  /// height * delta, and a turn by theta turns that shift into a translation error of 2 sin(theta / 2) * height *
  /// delta. One pair of views does not show the absolute tilt, so with delta = outdoor.tilt_prior_deg (the mount's
  /// rocking bound), a frame whose turn makes this more than sharp_turn_lever_m says `sharp_turn`, not `ok`
  /// (at 25 cm, 1 degree and 5 mm: turns of more than 70 degrees between frames). 0: off.
  double sharp_turn_lever_m = 0.005;
  /// A frame is `ok` only when its motion is right within ok_within_m and ok_within_deg. A fit whose own
  /// covariance allows more, ok_sigmas standard deviations of its heading or of its position along the worst
  /// direction, says `uncertain` instead (a fit of a few dozen keypoints on a weak floor, a turn measured from
  /// matches bunched in one corner). Only the label: the edge keeps its covariance. ok_sigmas 0: off.
  double ok_within_m = 0.005;
  double ok_within_deg = 0.5;
  double ok_sigmas = 3.0;
  /// A motion spanning at least this many frames' travel (its length over the last good motions' median length,
  /// or its time over the last good motion's) crossed frames that were dropped, with or without a trace in the
  /// timestamps: the frame says `gap`, not `ok` (the mount rocked over the gap, and one pair of views does not
  /// show how far). 0: off.
  double gap_min_steps = 2.0;
  /// Frames dropped without a trace leave one long motion; this many in a row, each spanning a gap, say the robot's
  /// step changed (it sped up, or the steps it was learnt from were wrong): their motions become the usual steps. Gaps
  /// the timestamps show do not count. 0: never; 1 would take every gap for a new speed.
  int speed_change_frames = 3;
  /// A fit refused for a rival transform (max_ambiguity) or for a motion unlike the robot's (a repeated floor:
  /// the true motion and its repetitions explain the matches alike) is decided by the robot's own motion
  /// (core/MotionPrior.hpp). Its usual step (the mean of the last good ones since the last sharp turn) once,
  /// turning as usual within repetition_step_turn_deg or on the spot (a sharp turn, see sharp_turn_lever_m),
  /// or k = 2 .. repetition_max_steps of them (frames dropped without a
  /// trace; k fixed when the timestamps show the gap) where k usual turns make the candidate's turn within
  /// repetition_turn_deg. A candidate's doubts: its distance to the nearest prediction over repetition_sigma_m +
  /// repetition_sigma_fraction * k * the step's length + the tilt's lever arm at its turn (see sharp_turn_lever_m).
  /// Candidates: the fit, RANSAC's rival repetitions and the fits to the matches near each prediction. The
  /// nearest is believed when at most repetition_max_doubts off with every other at least repetition_margin
  /// times as far (and that many doubts) off; a fit without rivals only where its turn fixes k. 0 steps: off.
  int repetition_max_steps = 8;
  double repetition_turn_deg = 1.0;
  double repetition_step_turn_deg = 5.0;
  double repetition_sigma_m = 0.004;
  double repetition_sigma_fraction = 0.2;
  double repetition_max_doubts = 1.0;
  double repetition_margin = 2.5;
  /// Failing that, the candidate within repetition_max_doubts with the most inliers is believed when it has this
  /// many times the inliers of every other candidate closer than repetition_margin * repetition_max_doubts
  /// (driving straight, a gap's repetition is some number of steps too, but overlaps the image less); one step
  /// with a sudden change of turn also needs no fewer inliers than any candidate. 0 = off.
  double repetition_support_ratio = 2.0;
  /// Tracking lost for the first time before the map holds this many frames: the map starts again at the lost
  /// frame, the frames before it are reported but left out (not measured, never places). Only at the first loss
  /// and the failing frames right after it: a floor that keeps losing the robot makes no map by starting again.
  /// 0: a lost segment is always relocalized.
  int restart_map_below_frames = 10;
  /// Where the map started again, the motions given up before it are measured again by aligning their images once the
  /// map can no longer start again (the usual step and the mean of the heading images known by then); each one
  /// believed joins its frame to the map, back to the first, which anchors the world frame.
  bool measure_given_up_frames = true;
  /// Right after tracking is lost for too little evidence on a floor that does not repeat, each frame up to this many
  /// after the last tracked one is measured against it (its features, else the images aligned); the first that is
  /// joins the lost segment to the map. 0: off.
  int bridge_max_frames = 3;
  /// Where every other bridge fails (tried last: they measure the motion better), a bridging frame's features with
  /// fewer inliers than a loop closure needs, but at least this many, are believed
  /// when their motion agrees with what the lost segment says since the last tracked frame (the loss frame placed by
  /// the robot's last good motion, then the segment's odometry through other images) within bridge_corroboration_m
  /// and _deg. 0: off (a fit needs 3 inliers whatever is set).
  int bridge_corroborated_min_inliers = 8;
  double bridge_corroboration_m = 0.003;    ///< the two agree within this,
  double bridge_corroboration_deg = 0.6;    ///< and this
  /// Where a bridging frame's features and image both fail (a quarter turn on the spot over a weak floor under a
  /// shadow that turns with it, a few frames dropped without a trace), the motions the robot can have made since
  /// the last tracked frame are searched (core/MotionSearch.hpp): one usual step and a turn on the spot, every
  /// this many degrees, or 1 to repetition_max_steps usual steps. The loss frame is searched too; two frames'
  /// results must agree through the lost segment's odometry. 0: off.
  double bridge_search_turn_deg = 5.0;  ///< 0, or 1 to 30 (a finer step multiplies the hypotheses)
  double bridge_search_radius_m = 0.008;  ///< features compared within this of where a hypothesis puts them
  int bridge_search_max_hamming = 80;     ///< a pair further apart is no match, bits
  double bridge_search_agreement_m = 0.01;   ///< two frames' searched motions agree within this,
  double bridge_search_agreement_deg = 2.0;  ///< and this
  /// Where the search finds nothing too, the bridging frame's image is registered with the last tracked one's by
  /// their spectra (the turn, core/SpectralTurn.hpp, then the shift from the phase correlation; Fourier-Mellin
  /// registration), both less the mean of the recent images. Believed, as the search is, once two frames agree;
  /// each must have a phase correlation peak of at least this, and twice the other half-turn's. 0: off.
  double bridge_spectral_min_peak = 0.15;
  /// A floor that repeats (tiles, bricks) is also told from its images (core/Repetition.hpp): every this many frames
  /// the image's repetition strength is measured, and once two checks in a row reach floor_repeat_min_strength the
  /// floor counts as repeating for the rest of the run. There a loss for a motion unlike the robot's (frames dropped
  /// without a trace) is not bridged: the gap's length is unknown, and a bridge lands one repetition short of it as
  /// readily as right. 0: never checked.
  int floor_repeat_check_frames = 10;
  /// Measured: 0.25-0.49 on tiles whose every tile carries one pattern, 0.20-0.37 on a photo of bricks, at most 0.19
  /// on asphalt, concrete, carpet and photos of gravel and grass.
  double floor_repeat_min_strength = 0.22;
  /// On a floor whose images repeat (floor_repeat_*), a motion the label does not vouch for (not `ok`) whose
  /// inliers fell below this share of the recent frames' median may be one repetition off: frames dropped where the
  /// fit found the tile before, so the overlap, and with it the inliers, fell. No prior-guided loop closure spans
  /// such a motion (LoopCloser::motionUnsure): the map's estimate, a loop's only guide among the repetitions, may be
  /// a tile off there. 0: off.
  double repeated_floor_unsure_inlier_share = 0.55;
};

/// Outdoors and on real robots: features that stay still in the image, and the camera's tilt and height per
/// frame (see core/StillFeatures.hpp and core/MountEstimation.hpp).
struct OutdoorConfig {
  bool reject_still = true;        ///< odometry ignores matches at the same place in both images while the rest say the robot moved
  double still_radius_px = 1.5;    ///< a match whose keypoints are this close in the image is still
  double moved_factor = 3.0;       ///< the robot moved when the fit moves the still matches by this many radii
  /// Loop closure and the map get no feature that stayed within still_radius_px of a feature this similar
  /// (bits) in the previous image while the fit moved it by moved_factor radii (the robot's own artifacts).
  int still_max_hamming = 40;
  ArtifactMaskSettings mask;       ///< image cells where still matches keep appearing
  bool estimate_mount = true;      ///< estimate roll, pitch and height per frame and project with them
  double tilt_prior_deg = 1.0;     ///< standard deviation of the tilt around the calibrated mount
  /// At the end of the run, every frame's roll, pitch and height are solved again from all the estimates at once
  /// (core/MountSmoother) and the trajectory is corrected for them.
  bool smooth_mount = true;
  /// With smooth_mount: each accepted loop closure's pair of views adds its factor too, tying the two frames'
  /// mounts across the run (the places keep their rays for it).
  bool mount_from_loops = true;
  /// With smooth_mount: every odometry step is fitted again at the end on a sample of its pairs through the two
  /// frames' final mounts, and the turn that the poses' corrections leave of the change applied to its edge (a tilt
  /// off sideways turns a step: the farther the step, the more).
  bool remeasure_odometry = true;
  double height_prior_m = 0.003;   ///< standard deviation of the height around the calibrated height
  /// Images give the height only relative to the reference frame's, so errors would add up frame after
  /// frame; each frame gives back this fraction of its difference from the calibrated height (a mount
  /// bounces around its calibrated height).
  double height_return = 0.1;
  double reference_sigma_deg = 0.2;  ///< how far a reference frame's estimated tilt may still move
  double point_sigma_px = 0.35;    ///< keypoint noise, pixels
  /// The previous frame's side of each pair is found by tracking the current keypoint into the previous image
  /// (core/PointTracking.hpp) rather than by its matched keypoint: a few hundredths of a pixel instead of most of one.
  bool track_points = true;
  double track_sigma_px = 0.1;     ///< noise of a tracked point, pixels of the tracking image (320 wide or less)
  /// Where the robot's own artifacts are seen, the odometry's heading is refined (odometry.align_heading_sigma_deg)
  /// on images of their own: reduced to this width or less, the background light removed with a blur of
  /// heading_highpass_fraction of it, and each pixel divided by the contrast around it, so that the ground in the
  /// shadow counts as much as the ground in the light and a glare's slope adds nothing (measured on the outdoor
  /// carpet lawnmower, consecutive frames aligned: 0.042 degrees RMS at 320 pixels and 2%, against 0.11 for the
  /// keypoints; the plain images at 160 pixels and 8% are off on most frames). Where nothing stays still they
  /// replace the alignment's reduced images when they have measured the turn clearly more precisely (a fine floor,
  /// carpet, that the reduced images blur away). 0: not refined there, nor used on clean floors.
  int heading_image_width_px = 320;
  double heading_highpass_fraction = 0.02;
  /// In those images, pixels where the background light changes by more than this share of its level over one blur
  /// width are left out: the shadow's edge turns with the heading and the high-pass leaves it as a line that pulls
  /// the turn (core/ImageAlignment.hpp light_edge_slope). 0: none are.
  double heading_light_edge_slope = 0.15;
  /// The tilt shows in the perspective between two views, more clearly the farther apart they are: the
  /// reference is the oldest recent frame within this fraction of the footprint's short side.
  double baseline_fraction = 0.4;
  double reference_match_radius_m = 0.006;  ///< guided matching to the reference around the odometry's prediction
  int max_pairs = 300;             ///< matches used per estimate
  double pair_radius_px = 2.5;     ///< a match enters the estimate when the SE(2) fit leaves it this close
  /// An estimate's own variance understates its error on hard images (blur, glare, few matches); this factor
  /// on it decides how much of the estimates' spread counts as noise.
  double variance_inflation = 2.0;
  /// The whole run's mounts are solved at the end (core/MountSmoother); an estimate whose misfit there exceeds the
  /// chi-square value a right one exceeds with this normal tail has its weight cut to that value over its weighted
  /// misfit and the run is solved again, five rounds at most (0: none is).
  double mount_outlier_z = 2.326;
};

struct Config {
  CameraConfig camera;
  OrbSettings features;
  MatcherSettings matching;
  FitSettings odometry;
  OdometryChecks odometry_checks;
  FallbackSettings fallback;
  LoopClosureSettings loop_closure;
  LocalizationSettings localization;
  OutdoorConfig outdoor;
  GraphConfig graph;
};

/// Allowed values of a numeric field.
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
};
constexpr Range kPositive{0.0, std::numeric_limits<double>::infinity(), true};
constexpr Range kNonNegative{0.0, std::numeric_limits<double>::infinity(), false};

/// Allowed values of a string field (the readers' input settings have some); empty: any string.
using Choices = std::vector<std::string>;
/// The constraint of an enum field: one of its values, each of which has a name in the YAML files (the names
/// are the readers' business: io/ConfigNames.hpp).
struct OneOfNames {};

/// The camera section describing a camera with the default straight-down mount at `mounting_height_m`.
CameraConfig cameraConfigOf(const CameraIntrinsics& intrinsics, double mounting_height_m);

/// The intrinsics a camera section describes.
CameraIntrinsics intrinsicsOf(const CameraConfig& camera);

/// Keys that a configuration must set (docs/conventions.md): "section.key".
const std::vector<std::string>& requiredConfigKeys();

/// "value V out of range [min, max]" (or "is not a finite number") when `value` is not allowed by `range`.
std::optional<std::string> rangeProblem(double value, const Range& range);

/// A key whose value cannot be used: "section.key" and what is wrong with it.
struct ConfigProblem {
  std::string key;
  std::string message;
};

/// The first problem of a configuration: a value outside its key's range or not finite, a camera mount that
/// is not rigid or does not see the ground, an ORB pyramid whose top level is smaller than a pixel.
std::optional<ConfigProblem> findConfigProblem(const Config& config);
/// Throws std::invalid_argument("section.key: what is wrong") for findConfigProblem's problem.
void validateConfig(const Config& config);

/// Calls visitor(section, key, field, constraint) for every field of the configuration.
template <class Config_, class Visitor>
void visitConfigFields(Config_& c, Visitor&& v) {
  v("camera", "image_width", c.camera.image_width, kPositive);
  v("camera", "image_height", c.camera.image_height, kPositive);
  v("camera", "fx", c.camera.fx, kPositive);
  v("camera", "fy", c.camera.fy, kPositive);
  v("camera", "cx", c.camera.cx, Range{});
  v("camera", "cy", c.camera.cy, Range{});
  v("camera", "distortion", c.camera.distortion, Range{});
  v("camera", "distortion_model", c.camera.distortion_model, OneOfNames{});
  v("camera", "mounting_height_m", c.camera.mounting_height_m, kPositive);
  v("camera", "T_robot_camera", c.camera.T_robot_camera, Range{});
  v("features", "num_features", c.features.num_features, Range{10, 100000});
  v("features", "scale_factor", c.features.scale_factor, Range{1.0, 4.0, true});
  v("features", "num_levels", c.features.num_levels, Range{1, 16});
  v("features", "fast_threshold", c.features.fast_threshold, Range{1, 255});
  v("features", "patch_size", c.features.patch_size, Range{3, 255});
  v("features", "edge_threshold", c.features.edge_threshold, Range{0, 255});
  v("features", "score_type", c.features.score_type, OneOfNames{});
  v("features", "near_twin_max_distance", c.features.near_twin_max_distance, Range{0, 256});
  v("features", "subpixel_window", c.features.subpixel_window, Range{0, 15});
  v("features", "flatten_window", c.features.flatten_window, Range{0.0, 1.0});
  v("features", "flatten_min_range", c.features.flatten_min_range, Range{0.0, 255.0});
  v("features", "max_extraction_width", c.features.max_extraction_width, Range{0, 100000});
  v("matching", "ratio", c.matching.ratio, Range{0.0, 1.0, true});
  v("matching", "method", c.matching.method, OneOfNames{});
  v("matching", "guided_odometry_radius_m", c.matching.guided_odometry_radius_m, kNonNegative);
  v("matching", "guided_min_inlier_fraction", c.matching.guided_min_inlier_fraction, Range{0.0, 1.0});
  v("odometry", "loss", c.odometry.loss, OneOfNames{});
  v("odometry", "loss_scale_m", c.odometry.loss_scale_m, kPositive);
  v("odometry", "min_inliers", c.odometry.min_inliers, Range{3, 100000});
  v("odometry", "ransac_inlier_m", c.odometry.ransac_inlier_m, kPositive);
  v("odometry", "ransac_iterations", c.odometry.ransac_iterations, Range{1, 1000000});
  v("odometry", "seed", c.odometry.seed, kNonNegative);
  v("odometry", "max_ambiguity", c.odometry_checks.max_ambiguity, Range{0.0, 1.0});
  v("odometry", "max_velocity_change_m", c.odometry_checks.max_velocity_change_m, kPositive);
  v("odometry", "max_velocity_change_fraction", c.odometry_checks.max_velocity_change_fraction, kNonNegative);
  v("odometry", "decisive_inlier_share", c.odometry_checks.decisive_inlier_share, Range{0.0, 2.0});
  v("odometry", "low_overlap_ratio", c.odometry_checks.low_overlap_ratio, Range{0.0, 1.0});
  v("odometry", "low_overlap_max_ambiguity", c.odometry_checks.low_overlap_max_ambiguity, Range{0.0, 1.0});
  v("odometry", "low_overlap_max_match_share", c.odometry_checks.low_overlap_max_match_share, Range{0.0, 1.0});
  v("odometry", "low_overlap_sigma_m", c.odometry_checks.low_overlap_sigma_m, kNonNegative);
  v("odometry", "low_overlap_sigma_rad", c.odometry_checks.low_overlap_sigma_rad, kNonNegative);
  v("odometry", "align_images", c.odometry_checks.align_images, Range{});
  v("odometry", "align_width_px", c.odometry_checks.align_width_px, Range{16, 100000});
  v("odometry", "align_highpass_fraction", c.odometry_checks.align_highpass_fraction, Range{0.001, 1.0});
  v("odometry", "align_normalise_contrast", c.odometry_checks.align_normalise_contrast, Range{});
  v("odometry", "align_min_correlation", c.odometry_checks.align_min_correlation, Range{0.0, 1.0});
  v("odometry", "align_heading_images_min_correlation", c.odometry_checks.align_heading_images_min_correlation, Range{0.0, 1.0});
  v("odometry", "align_rest_ratio", c.odometry_checks.align_rest_ratio, kNonNegative);
  v("odometry", "align_max_spread_m", c.odometry_checks.align_max_spread_m, kPositive);
  v("odometry", "align_sigma_m", c.odometry_checks.align_sigma_m, kNonNegative);
  v("odometry", "align_sigma_rad", c.odometry_checks.align_sigma_rad, kNonNegative);
  v("odometry", "align_min_step_share", c.odometry_checks.align_min_step_share, kNonNegative);
  v("odometry", "rest_check_by_spectra", c.odometry_checks.rest_check_by_spectra, Range{});
  v("odometry", "gap_by_spectra", c.odometry_checks.gap_by_spectra, Range{});
  v("odometry", "align_check_below_inliers", c.odometry_checks.align_check_below_inliers, Range{0, 1000000});
  v("odometry", "align_check_m", c.odometry_checks.align_check_m, kNonNegative);
  v("odometry", "align_check_rad", c.odometry_checks.align_check_rad, kNonNegative);
  v("odometry", "align_check_radius_m", c.odometry_checks.align_check_radius_m, kPositive);
  v("odometry", "align_check_support", c.odometry_checks.align_check_support, kNonNegative);
  v("odometry", "align_confirm_below_inliers", c.odometry_checks.align_confirm_below_inliers, Range{0, 1000000});
  v("odometry", "unconfirmed_gap_min_inlier_share", c.odometry_checks.unconfirmed_gap_min_inlier_share, Range{0.0, 1.0});
  v("odometry", "align_heading_sigma_deg", c.odometry_checks.align_heading_sigma_deg, kNonNegative);
  v("odometry", "finer_heading_images", c.odometry_checks.finer_heading_images, Range{});
  v("odometry", "sharp_turn_lever_m", c.odometry_checks.sharp_turn_lever_m, kNonNegative);
  v("odometry", "ok_within_m", c.odometry_checks.ok_within_m, kPositive);
  v("odometry", "ok_within_deg", c.odometry_checks.ok_within_deg, kPositive);
  v("odometry", "ok_sigmas", c.odometry_checks.ok_sigmas, kNonNegative);
  v("odometry", "gap_min_steps", c.odometry_checks.gap_min_steps, kNonNegative);
  v("odometry", "speed_change_frames", c.odometry_checks.speed_change_frames, Range{0, 1000});
  v("odometry", "repetition_max_steps", c.odometry_checks.repetition_max_steps, Range{0, 1000});
  v("odometry", "repetition_turn_deg", c.odometry_checks.repetition_turn_deg, kNonNegative);
  v("odometry", "repetition_step_turn_deg", c.odometry_checks.repetition_step_turn_deg, kNonNegative);
  v("odometry", "repetition_sigma_m", c.odometry_checks.repetition_sigma_m, kPositive);
  v("odometry", "repetition_sigma_fraction", c.odometry_checks.repetition_sigma_fraction, kNonNegative);
  v("odometry", "repetition_max_doubts", c.odometry_checks.repetition_max_doubts, kPositive);
  v("odometry", "repetition_margin", c.odometry_checks.repetition_margin, Range{1.0, 1000.0});
  v("odometry", "repetition_support_ratio", c.odometry_checks.repetition_support_ratio, kNonNegative);
  v("odometry", "restart_map_below_frames", c.odometry_checks.restart_map_below_frames, Range{0, 1e9});
  v("odometry", "measure_given_up_frames", c.odometry_checks.measure_given_up_frames, Range{});
  v("odometry", "bridge_max_frames", c.odometry_checks.bridge_max_frames, Range{0, 1000});
  v("odometry", "bridge_corroborated_min_inliers", c.odometry_checks.bridge_corroborated_min_inliers, Range{0, 100000});
  v("odometry", "bridge_corroboration_m", c.odometry_checks.bridge_corroboration_m, kPositive);
  v("odometry", "bridge_corroboration_deg", c.odometry_checks.bridge_corroboration_deg, kPositive);
  v("odometry", "bridge_search_turn_deg", c.odometry_checks.bridge_search_turn_deg, Range{0.0, 30.0});
  v("odometry", "bridge_search_radius_m", c.odometry_checks.bridge_search_radius_m, Range{0.0, 0.05, true});
  v("odometry", "bridge_search_max_hamming", c.odometry_checks.bridge_search_max_hamming, Range{0, 256});
  v("odometry", "bridge_search_agreement_m", c.odometry_checks.bridge_search_agreement_m, kPositive);
  v("odometry", "bridge_search_agreement_deg", c.odometry_checks.bridge_search_agreement_deg, kPositive);
  v("odometry", "bridge_spectral_min_peak", c.odometry_checks.bridge_spectral_min_peak, Range{0.0, 1.0});
  v("odometry", "floor_repeat_check_frames", c.odometry_checks.floor_repeat_check_frames, Range{0, 1000000});
  v("odometry", "floor_repeat_min_strength", c.odometry_checks.floor_repeat_min_strength, Range{0.0, 1.0});
  v("odometry", "repeated_floor_unsure_inlier_share", c.odometry_checks.repeated_floor_unsure_inlier_share, Range{0.0, 1.0});
  v("odometry", "fallback_sigma_m", c.fallback.sigma_m, kPositive);
  v("odometry", "fallback_sigma_rad", c.fallback.sigma_rad, kPositive);
  v("odometry", "fallback_turn_min_inliers", c.fallback.turn_min_inliers, Range{0, 1000000});
  v("odometry", "fallback_likeliest_motion", c.fallback.likeliest_motion, Range{});
  v("odometry", "fallback_turn_image_width_px", c.fallback.turn_image_width_px, Range{0, 100000});
  v("odometry", "fallback_turn_min_peak_ratio", c.fallback.turn_min_peak_ratio, Range{1.0, 1e9});
  v("odometry", "fallback_turn_half_turn_ratio", c.fallback.turn_half_turn_ratio, Range{1.0, 1e9});
  v("odometry", "fallback_turn_min_margin_deg", c.fallback.turn_min_margin_deg, Range{0.0, 90.0});
  v("odometry", "fallback_turn_background_frames", c.fallback.turn_background_frames, Range{1, 100000});
  v("odometry", "fallback_motion_by_spectra", c.fallback.motion_by_spectra, Range{});
  v("loop_closure", "enabled", c.loop_closure.enabled, Range{});
  v("loop_closure", "database_delay_frames", c.loop_closure.database_delay_frames, Range{1, 1e9});
  v("loop_closure", "max_candidates", c.loop_closure.max_candidates, Range{0, 1000});
  v("loop_closure", "max_nearby_places", c.loop_closure.max_nearby_places, Range{0, 100000});
  v("loop_closure", "max_global_candidates", c.loop_closure.max_global_candidates, Range{0, 1000});
  v("loop_closure", "max_accepted_per_frame", c.loop_closure.max_accepted_per_frame, Range{1, 1000});
  v("loop_closure", "loop_spacing_m", c.loop_closure.loop_spacing_m, kNonNegative);
  v("loop_closure", "search_radius_m", c.loop_closure.search_radius_m, kNonNegative);
  v("loop_closure", "max_search_radius_m", c.loop_closure.max_search_radius_m, Range{0.0, 10.0});
  v("loop_closure", "place_spacing_m", c.loop_closure.place_spacing_m, kNonNegative);
  v("loop_closure", "min_bow_score", c.loop_closure.min_bow_score, Range{0.0, 1.0});
  v("loop_closure", "min_matches", c.loop_closure.min_matches, Range{3, 1e9});
  v("loop_closure", "min_inliers", c.loop_closure.min_inliers, Range{3, 1e9});
  v("loop_closure", "max_covariance_score", c.loop_closure.max_covariance_score, Range{-30.0, 30.0});
  v("loop_closure", "max_ambiguity", c.loop_closure.max_ambiguity, Range{0.0, 1.0});
  v("loop_closure", "max_disagreement_m", c.loop_closure.max_disagreement_m, kPositive);
  v("loop_closure", "max_disagreement_per_m", c.loop_closure.max_disagreement_per_m, kNonNegative);
  v("loop_closure", "max_disagreement_rad", c.loop_closure.max_disagreement_rad, kPositive);
  v("loop_closure", "max_disagreement_rad_per_m", c.loop_closure.max_disagreement_rad_per_m, kNonNegative);
  v("loop_closure", "refine_by_tracked_points", c.loop_closure.refine_by_tracked_points, Range{});
  v("loop_closure", "tilt_sigma_deg", c.loop_closure.tilt_sigma_deg, kNonNegative);
  v("loop_closure", "rescue_min_inliers", c.loop_closure.rescue_min_inliers, Range{0, 1e9});
  v("loop_closure", "remeasure_at_end", c.loop_closure.remeasure_at_end, Range{});
  v("loop_closure", "lost_reach_m", c.loop_closure.lost_reach_m, kNonNegative);
  v("loop_closure", "lost_reach_deg", c.loop_closure.lost_reach_deg, Range{0.0, 180.0});
  v("localization", "cell_m", c.localization.cell_m, Range{0.001, 0.1});
  v("localization", "cell_deg", c.localization.cell_deg, Range{0.5, 45.0});
  v("localization", "max_hamming", c.localization.max_hamming, Range{0, 256});
  v("localization", "max_postings", c.localization.max_postings, Range{1, 1e9});
  v("localization", "max_peaks", c.localization.max_peaks, Range{1, 100});
  v("localization", "min_votes", c.localization.min_votes, Range{1, 1e9});
  v("localization", "max_rival_ratio", c.localization.max_rival_ratio, Range{0.0, 1.0});
  v("localization", "max_vote_ratio", c.localization.max_vote_ratio, Range{0.0, 1.0});
  v("localization", "unrepeated_max_vote_ratio", c.localization.unrepeated_max_vote_ratio, Range{0.0, 1.0});
  v("localization", "min_inliers", c.localization.min_inliers, Range{3, 1e9});
  v("localization", "strong_hamming", c.localization.strong_hamming, Range{0, 256});
  v("localization", "min_strong_inliers", c.localization.min_strong_inliers, Range{0, 1e9});
  v("localization", "max_covariance_score", c.localization.max_covariance_score, Range{-30.0, 30.0});
  v("localization", "min_spread", c.localization.min_spread, Range{0.0, 1.0});
  v("localization", "match_radius_m", c.localization.match_radius_m, kPositive);
  v("localization", "ratio", c.localization.ratio, Range{0.0, 1.0, true});
  v("localization", "footprint_radius_m", c.localization.footprint_radius_m, kPositive);
  v("localization", "max_odometry_disagreement_m", c.localization.max_odometry_disagreement_m, kPositive);
  v("localization", "max_odometry_disagreement_rad", c.localization.max_odometry_disagreement_rad, kPositive);
  v("localization", "every_frames", c.localization.every_frames, Range{1, 1e9});
  v("localization", "min_anchor_offset_m", c.localization.min_anchor_offset_m, kNonNegative);
  v("localization", "min_anchor_offset_rad", c.localization.min_anchor_offset_rad, kNonNegative);
  v("localization", "repeated_floor_baseline_m", c.localization.repeated_floor_baseline_m, kNonNegative);
  v("localization", "measure_on_keyframe", c.localization.measure_on_keyframe, Range{});
  v("outdoor", "reject_still", c.outdoor.reject_still, Range{});
  v("outdoor", "still_radius_px", c.outdoor.still_radius_px, Range{0.0, 50.0});
  v("outdoor", "moved_factor", c.outdoor.moved_factor, Range{1.0, 100.0});
  v("outdoor", "still_max_hamming", c.outdoor.still_max_hamming, Range{0, 256});
  v("outdoor", "mask_cells_x", c.outdoor.mask.cells_x, Range{1, 1000});
  v("outdoor", "mask_cells_y", c.outdoor.mask.cells_y, Range{1, 1000});
  v("outdoor", "mask_fade", c.outdoor.mask.fade, Range{0.0, 1.0});
  v("outdoor", "mask_min_evidence", c.outdoor.mask.min_evidence, kPositive);
  v("outdoor", "estimate_mount", c.outdoor.estimate_mount, Range{});
  v("outdoor", "tilt_prior_deg", c.outdoor.tilt_prior_deg, Range{0.0, 45.0, true});
  v("outdoor", "smooth_mount", c.outdoor.smooth_mount, Range{});
  v("outdoor", "mount_from_loops", c.outdoor.mount_from_loops, Range{});
  v("outdoor", "remeasure_odometry", c.outdoor.remeasure_odometry, Range{});
  v("outdoor", "height_prior_m", c.outdoor.height_prior_m, kPositive);
  v("outdoor", "height_return", c.outdoor.height_return, Range{0.0, 1.0});
  v("outdoor", "reference_sigma_deg", c.outdoor.reference_sigma_deg, Range{0.0, 45.0, true});
  v("outdoor", "point_sigma_px", c.outdoor.point_sigma_px, kPositive);
  v("outdoor", "track_points", c.outdoor.track_points, Range{});
  v("outdoor", "track_sigma_px", c.outdoor.track_sigma_px, kPositive);
  v("outdoor", "heading_image_width_px", c.outdoor.heading_image_width_px, Range{0, 100000});
  v("outdoor", "heading_highpass_fraction", c.outdoor.heading_highpass_fraction, Range{0.001, 1.0});
  v("outdoor", "heading_light_edge_slope", c.outdoor.heading_light_edge_slope, kNonNegative);
  v("outdoor", "max_pairs", c.outdoor.max_pairs, Range{3, 100000});
  v("outdoor", "pair_radius_px", c.outdoor.pair_radius_px, kPositive);
  v("outdoor", "variance_inflation", c.outdoor.variance_inflation, Range{1.0, 100.0});
  v("outdoor", "mount_outlier_z", c.outdoor.mount_outlier_z, Range{0.0, 10.0});
  v("outdoor", "baseline_fraction", c.outdoor.baseline_fraction, Range{0.0, 1.0});
  v("outdoor", "reference_match_radius_m", c.outdoor.reference_match_radius_m, kPositive);
  v("graph", "min_sigma_m", c.graph.min_sigma_m, kNonNegative);
  v("graph", "min_sigma_rad", c.graph.min_sigma_rad, kNonNegative);
  v("graph", "optimise_every_frames", c.graph.optimise_every_frames, Range{1, 1e9});
  v("graph", "window_frames", c.graph.window_frames, Range{0, 1e9});
  v("graph", "full_optimisation_correction_m", c.graph.full_optimisation_correction_m, kNonNegative);
  v("graph", "loop_loss_scale", c.graph.solver.loop_loss_scale, kPositive);
  v("graph", "max_iterations", c.graph.solver.max_iterations, Range{1, 10000});
}

}  // namespace groundslam
