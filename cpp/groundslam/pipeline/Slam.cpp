#include "groundslam/pipeline/Slam.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "groundslam/pipeline/StageTimer.hpp"

namespace groundslam {
namespace {

/// Splits matched features into the two point lists a rigid fit takes.
std::pair<std::vector<Eigen::Vector2d>, std::vector<Eigen::Vector2d>> matchedPoints(const std::vector<Match>& matches,
                                                                                    const GroundFeatures& query,
                                                                                    const GroundFeatures& train) {
  std::vector<Eigen::Vector2d> train_points, query_points;
  for (const Match& m : matches) {
    train_points.push_back(train.points[static_cast<size_t>(m.train)]);
    query_points.push_back(query.points[static_cast<size_t>(m.query)]);
  }
  return {train_points, query_points};
}

/// An edge that keeps the graph connected (and a new segment's frame defined) without claiming to know the
/// motion: a standard deviation of 100 m and 100 rad.
GraphEdge informationFreeEdge(int from, int to, const Pose2& T_from_to) {
  return {from, to, T_from_to, Eigen::Vector3d(1e-4, 1e-4, 1e-4).asDiagonal(), false};
}

}  // namespace

Slam::Slam(const Config& config, std::shared_ptr<const Vocabulary> vocabulary)
    : config_((validateConfig(config), config)),
      odometry_fitting_(config.odometry),
      preparer_(config),
      matcher_(config.matching),
      camera_(cameraModelFrom(config.camera)),
      calibrated_mount_(camera_.T_robot_camera()),
      ground_sample_m_(camera_.groundSampleDistance()),
      artifact_mask_(intrinsicsOf(config.camera), config.outdoor.mask),
      graph_(config.graph.solver),
      alignment_settings_(alignmentSettingsFrom(config)) {
  plain_headings_.settings = alignment_settings_;
  image_turn_sign_ = imageTurnSign(camera_, intrinsicsOf(config.camera));
  artifact_headings_.settings = headingImageSettingsFrom(config);
  artifact_headings_.narrows_variance = false;
  fine_headings_.settings = artifact_headings_.settings;
  odometry_fitting_.measure_ambiguity = true;
  const CameraIntrinsics k = intrinsicsOf(config.camera);
  mount_baseline_m_ = config.outdoor.baseline_fraction * std::min(k.width, k.height) * ground_sample_m_;
  mount_pair_radius_m_ = config.outdoor.pair_radius_px * ground_sample_m_;
  odometry_fitting_.rival_max_rotation_rad = 1.0 * M_PI / 180.0;
  // Not in the paper: a rival made of matches that stayed in place is the robot's own artifacts, not the floor.
  if (config.outdoor.reject_still) {
    odometry_fitting_.rival_min_motion_m = config.outdoor.moved_factor * config.outdoor.still_radius_px * ground_sample_m_;
  }
  if (config.loop_closure.enabled && vocabulary && !vocabulary->empty()) {
    loop_closer_.emplace(config.loop_closure, std::move(vocabulary), config.matching, config.odometry, config.localization);
  }
}

FrameResult Slam::process(const cv::Mat& image, double timestamp) { return process(prepareFrame(image, timestamp)); }

FrameResult Slam::process(PreparedFrame prepared) {
  StageTimer total;
  FrameResult result;
  const int frame = static_cast<int>(timestamps_.size());  // graph index: a prior map's keyframes come first
  result.index = frame - prior_frames_;
  result.timestamp = prepared.timestamp;
  result.keypoints = static_cast<int>(prepared.features.size());
  result.times.extract_ms = prepared.extract_ms;
  result.times.project_ms = prepared.project_ms;
  timestamps_.push_back(prepared.timestamp);
  Keyframe current{frame, prepared.timestamp, std::move(prepared.features), calibratedState(calibrated_mount_)};
  if (prepared.matches_to_previous) result.times.match_ms = prepared.match_ms;

  noteRepetition(result.index, prepared.turn);
  std::vector<Match> still;  // matches of this frame to the previous one that stayed still in the image
  bool tied_to_previous = false;  // odometry measured this frame's motion: it is in the previous frame's segment
  // §III-B: match to the previous image, fit T_prev_curr with a robust M-estimator (eqs. 5-6), add the edge.
  if (previous_) {
    OdometryEdge odometry = estimateOdometry(*previous_, current, prepared, result);
    if (odometry.fallback && !odometry.turn_measured && !motionBySpectraAssumed(odometry, current, prepared)) {
      turnBySpectra(odometry, prepared.turn);
    }
    // Not in the paper: every match in place while the images show the ground moving is the robot's own artifacts.
    if (auto moving = restRefuted(*previous_, current, odometry, prepared)) odometry = std::move(*moving);
    // Not in the paper: too few matches among all features after frames dropped; the spectra show where to look.
    if (auto measured = gapBySpectra(*previous_, current, odometry, prepared)) {
      odometry = std::move(*measured);
      if (odometry.low_overlap) result.inliers = odometry.inliers;  // an alignment keeps the failed fit's count
    }
    // Only where something already stayed still (a still match, an artifact cell): a clean floor pays nothing.
    const bool artifacts_seen = result.still_matches > 0 || artifact_mask_.artifactCells() > 0;
    if (!odometry.fallback && artifacts_seen) still = stillFeatures(*previous_, current, odometry.T_prev_curr);
    // Points are tracked through the robot's shadow, glare and dirt too: the tracker compares each window's texture,
    // not its light, and leaves out windows near what stays still (core/PointTracking.hpp).
    if (!odometry.fallback && !odometry.aligned && config_.outdoor.estimate_mount) {
      estimateMountOf(*previous_, current, odometry, prepared.tracking, result);
    }
    // Where something stays still in the image (the robot's shadow, glare, dirt or bumper), the alignment's plain
    // images pull toward rest and are off on most frames (measured outdoors: 1-5% of the turns lost); images whose
    // contrast is normalised, finer and less blurred, are not (outdoor.heading_image_width_px).
    // The label judges the keypoints' fit: the images refine its heading, not its position, and a weak fit they
    // contradict is not vouched for.
    bool vouched = vouchedFor(odometry, current);
    const Pose2 fitted = odometry.T_prev_curr;  // before the images refine it: refineEarlyHeadings starts from it
    const Eigen::Matrix3d fitted_covariance = odometry.covariance;
    HeadingImages* heading_source = nullptr;    // the kind of heading image measured for the edge in use
    if (!odometry.fallback && !odometry.aligned && !odometry.low_overlap) {
      StageTimer timer;
      bool contradicted = false;
      if (artifacts_seen) {
        heading_source = &artifact_headings_;
        contradicted = refineHeadingByImages(odometry, current, previous_heading_, prepared.heading, artifact_headings_);
      } else {
        // Where nothing stays still: the alignment's reduced images, or the finer heading images where those measure
        // the turn more precisely (a fine texture such as carpet, which the reduced images blur away). Each learns
        // its precision on its own; the one not in use is measured on every kFineHeadingCheckFrames-th frame.
        const bool fine = finerHeadingImagesBetter();
        heading_source = fine ? &fine_headings_ : &plain_headings_;
        const bool check = config_.odometry_checks.finer_heading_images &&
                           (fine_headings_.count < kLearntHeadings || fine_check_count_++ % kFineHeadingCheckFrames == 0);
        OdometryEdge probe;  // the kind not in use refines a copy, made only when it is measured
        if (check) probe = odometry;
        if (fine || check) {
          OdometryEdge& target = fine ? odometry : probe;
          contradicted = refineHeadingByImages(target, current, previous_heading_, prepared.heading, fine_headings_) && fine;
        }
        if (!fine || check) {
          OdometryEdge& target = fine ? probe : odometry;
          contradicted = (refineHeadingByImages(target, current, previous_alignment_, prepared.alignment, plain_headings_) && !fine) ||
                         contradicted;
        }
      }
      if (contradicted && config_.odometry_checks.ok_sigmas > 0.0) vouched = false;  // ok_sigmas 0: the label is off
      result.times.fit_ms += timer.lap();
    }
    result.odometry = odometry.T_prev_curr;
    rocking_steps_.resize(static_cast<size_t>(frame) + 1, 1.0);
    // Only a gap counts: between frames the mount rocks as it does at any speed (measured: with every speed change
    // counted, the standard asphalt random walk's 0.7-1.2 cm steps made its ATE 1.32 -> 1.37 mm).
    const double steps = rockingSteps(odometry, previous_->timestamp, current.timestamp);
    rocking_steps_[static_cast<size_t>(frame)] = spansGap(steps) ? steps : 1.0;
    if (!odometry.fallback && !odometry.low_overlap) {
      last_good_odometry_ = odometry;
      const int speed_change_frames = config_.odometry_checks.speed_change_frames;
      if (spansGap(steps)) {
        // Over a gap the robot's step is the motion shared among the steps, and a step takes as long as before.
        const Pose2& T = odometry.T_prev_curr;
        last_good_odometry_->T_prev_curr = Pose2(T.x / steps, T.y / steps, T.theta / steps);
        // A gap the timestamps show is explained by them: only one told by the motion's length may be a new speed.
        const bool timed_gap = last_good_odometry_seconds_ > 0.0 &&
                               spansGap((current.timestamp - previous_->timestamp) / last_good_odometry_seconds_);
        if (timed_gap) long_steps_.clear();
        else if (speed_change_frames > 0) long_steps_.push_back(T);
      } else {
        last_good_odometry_seconds_ = current.timestamp - previous_->timestamp;
        long_steps_.clear();
      }
      // A turn on the spot may change the direction of the robot's steps as its camera sees them.
      if (sharpTurn(odometry.T_prev_curr)) before_turn_ = std::make_pair(usualStep(), odometry.T_prev_curr.theta);
      if (speed_change_frames > 0 && long_steps_.size() >= static_cast<size_t>(speed_change_frames)) {
        // Not in the paper: frames dropped without a trace leave one long motion, not several in a row. These say the
        // usual step is what changed: the robot sped up, or the steps it was learnt from were wrong (on a faint floor
        // a few early fits of 2-3 mm had every later 1 cm step taken for a gap of 3-4 steps, shared out again as 2.7
        // mm, for the rest of the run). Their motions are the robot's steps from now on (the last kRecentSteps).
        const size_t kept = std::min(long_steps_.size(), kRecentSteps);
        recent_steps_.assign(long_steps_.end() - static_cast<std::ptrdiff_t>(kept), long_steps_.end());
        last_good_odometry_->T_prev_curr = odometry.T_prev_curr;
        last_good_odometry_seconds_ = current.timestamp - previous_->timestamp;
        long_steps_.clear();
      } else {
        recent_steps_.push_back(last_good_odometry_->T_prev_curr);
        if (recent_steps_.size() > kRecentSteps) recent_steps_.pop_front();
      }
      steps_since_turn_ = sharpTurn(odometry.T_prev_curr) ? 0 : steps_since_turn_ + 1;
    } else {
      // The speed is unknown again (a low-overlap motion usually spans a gap): the next motion is not judged by it.
      last_good_odometry_seconds_ = 0.0;
      long_steps_.clear();
    }
    // Only at the run's first loss (and the frames right after it that fail too: a covered lens): a floor that
    // keeps losing the robot makes no map by starting again.
    const bool restart = odometry.fallback && loop_closer_ && prior_frames_ == 0 && (!ever_lost_ || map_start_ == frame - 1) &&
                         frame < config_.odometry_checks.restart_map_below_frames;
    if (restart) {
      restartMap(odometry);  // lost before there is a map to come back to: the map starts here
    } else if (odometry.fallback && loop_closer_) {
      startSegment(odometry);  // tracking lost: the motion is unknown, global localization will find the pose
    } else {
      addToGraph(odometry);
      keepOdometryPairs(odometry, *previous_, current);
      // While the heading images learn their variance, the keypoints' fit is kept for refineEarlyHeadings.
      const auto measured_now = [frame](const HeadingImages& h) { return !h.early.empty() && h.early.back().frame == frame; };
      if (measured_now(plain_headings_) || measured_now(fine_headings_) || measured_now(artifact_headings_)) {
        early_fits_[frame] = {graph_.edges().size() - 1, fitted, fitted_covariance};
      }
      if (heading_source != nullptr) refineEarlyHeadings(*heading_source);
    }
    result.status = lost_ || restart      ? FrameStatus::lost
                    : odometry.fallback   ? FrameStatus::fallback
                    : odometry.low_overlap ? FrameStatus::low_overlap
                    : odometry.aligned ? FrameStatus::aligned
                    : odometry.unconfirmed ? FrameStatus::unconfirmed
                    : sharpTurn(odometry.T_prev_curr) ? FrameStatus::sharp_turn
                    : spansGap(steps) ? FrameStatus::gap
                    : !vouched ? FrameStatus::uncertain
                                          : FrameStatus::ok;
    if (odometry.fallback) result.fallback_reason = odometry.fit_status;
    if (loop_closer_ && mayBeARepetitionOff(result)) loop_closer_->motionUnsure();
    if (!odometry.fallback && !odometry.used.empty() && !atRest(odometry.T_prev_curr, odometry.used, current)) seen_moving_ = true;
    tied_to_previous = !odometry.fallback;
    measured_.push_back((!odometry.fallback && !lost_) || map_start_ == frame);
  } else if (prior_frames_ > 0) {
    // On a prior map the first frame's pose is unknown until global localization finds it.
    graph_.addPose(Pose2());
    graph_.addEdge(informationFreeEdge(0, frame, Pose2()));
    result.status = FrameStatus::lost;
    measured_.push_back(false);
  } else {
    graph_.addPose(Pose2());
    result.status = FrameStatus::first;
    measured_.push_back(true);
  }

  result.mount = current.mount;
  if (used_mounts_.size() <= static_cast<size_t>(frame)) used_mounts_.resize(static_cast<size_t>(frame) + 1, calibratedState(calibrated_mount_));
  used_mounts_[static_cast<size_t>(frame)] = current.mount;
  result.artifact_cells = artifact_mask_.artifactCells();

  // §III-C: loop closures through the three gates become graph edges; the graph is optimised (LM). What
  // stays still in the image is not ground: the places and the map get neither artifact cells nor still features.
  const Keyframe ground = groundOf(current, still);
  closeLoops(ground, prepared.tracking, result);
  keepPlaceTracking(frame, prepared.tracking);
  if (lost_) {
    relocalize(ground, result);
    if (lost_) bridgeLoss(current, prepared, result);
  } else if (prior_frames_ > 0) closeLoopsOnPriorMap(ground, result);
  optimiseIfDue(result, false);
  if (prior_frames_ == 0) {
    keepEarlyImages(frame, prepared);
    remeasureGivenUpFrames(frame);
  }
  // Once the map holds the segment just found in place: segments lost again before they were found may lie on its
  // ground.
  if (orphans_due_ && !lost_) joinOrphanSegments(result);

  result.T_world_robot = graph_.poses().back();
  if (lost_ || !measuredByOdometry(result.status)) recent_.clear();
  if (!lost_ && config_.outdoor.estimate_mount) {
    recent_.push_back(current);
    while (recent_.size() > 30) recent_.pop_front();
  }
  previous_ = std::move(current);
  // Inside a lost segment too, once the frames right after its loss have had their bridge to the frame before it.
  const bool in_lost_segment = lost_ && tied_to_previous && frame >= lost_since_ + config_.odometry_checks.bridge_max_frames;
  if ((!lost_ && measured_.back()) || in_lost_segment) {
    tracked_keyframe_ = previous_;
    tracked_alignment_ = prepared.alignment;  // shares the pixels: neither is changed
    tracked_heading_ = prepared.heading;
    tracked_turn_image_ = prepared.turn;
    tracked_frame_ = frame;
    tracked_time_ = prepared.timestamp;
    tracked_segment_ = lost_ ? segment_ : kMapSegment;
    tracked_segment_start_ = lost_since_;
  }
  previous_alignment_ = std::move(prepared.alignment);
  keepHeadingImage(prepared.heading);
  previous_heading_ = std::move(prepared.heading);
  keepTurnImage(std::move(prepared.turn));
  previous_tracking_ = std::move(prepared.tracking);
  result.times.total_ms = prepared.extract_ms + prepared.project_ms + total.lap();
  return result;
}

std::vector<Match> Slam::stillFeatures(const Keyframe& previous, const Keyframe& current, const Pose2& T_prev_curr) const {
  const OutdoorConfig& o = config_.outdoor;
  if (o.still_max_hamming <= 0) return {};
  const double moved_m = movedDistanceM();
  std::vector<Match> still;
  for (const Match& m : findStillFeatures(current.features, previous.features, o.still_radius_px / config_.camera.fx, o.still_max_hamming)) {
    // Only where the motion should have moved the feature: near a turn's centre the ground itself stays put.
    const Eigen::Vector2d& p = current.features.points[static_cast<size_t>(m.query)];
    if ((T_prev_curr * p - p).norm() >= moved_m) still.push_back(m);
  }
  return still;
}

Keyframe Slam::groundOf(const Keyframe& current, const std::vector<Match>& still) {
  std::vector<bool> moving(current.features.size(), true);
  for (const Match& m : still) moving[static_cast<size_t>(m.query)] = false;
  Keyframe ground{current.index, current.timestamp,
                  artifact_mask_.withoutArtifacts(still.empty() ? current.features : selectFeatures(current.features, moving)),
                  current.mount};
  // Places keep the rays only for what fits a loop's pair of views through the frames' mounts: the mount solved over
  // the run (a loop closure's pair of views is a factor) and the loop measured on its pairs again.
  if (!mountFromLoops() && !loopsKeepRays()) ground.features.rays.clear();
  if (loop_closer_ && previous_ && !still.empty()) {
    // The previous frame's side of the same matches (its first frame's included, which no match had judged yet).
    std::vector<Eigen::Vector2d> previous_still;
    for (const Match& m : still) previous_still.push_back(previous_->features.points[static_cast<size_t>(m.train)]);
    loop_closer_->forgetPendingFeatures(previous_->index, previous_still);
  }
  return ground;
}

void Slam::finish() {
  FrameResult ignored;
  optimiseIfDue(ignored, true);
  if (config_.outdoor.estimate_mount && config_.outdoor.smooth_mount) {
    smoothMount();
    const bool steps_changed = remeasureOdometry();
    const bool loops_changed = remeasureLoops();
    if (steps_changed || loops_changed) graph_.optimise();
  }
}

void Slam::addToGraph(const OdometryEdge& odometry) {
  const int from = static_cast<int>(graph_.poses().size()) - 1;
  const int to = graph_.addPose(graph_.poses().back() * odometry.T_prev_curr);
  graph_.addEdge({from, to, odometry.T_prev_curr,
                  informationFrom(odometry.covariance, config_.graph.min_sigma_m, config_.graph.min_sigma_rad), false});
}

int Slam::addUnmeasuredMotion(const OdometryEdge& failed) {
  const int from = static_cast<int>(graph_.poses().size()) - 1;
  const int to = graph_.addPose(graph_.poses().back() * failed.T_prev_curr);
  graph_.addEdge(informationFreeEdge(from, to, failed.T_prev_curr));
  return to;
}

void Slam::startSegment(const OdometryEdge& failed) {
  // The relocalization edge, not this one, will decide where the new segment lies.
  const int to = addUnmeasuredMotion(failed);
  // The bridge believes only what a loop closure would, over the time between the two frames.
  bridgeable_loss_ = bridgeableLoss(failed.fit_status, repetitionShown(to), floor_looks_repeated_);
  loop_closer_->trackingLost(graph_.poses());
  pending_search_.reset();
  ever_lost_ = true;
  segment_ = ++segments_started_;  // never one used before: an earlier lost segment may still wait to join
  lost_ = true;
  lost_since_ = to;
}

void Slam::restartMap(const OdometryEdge& failed) {
  // The frames so far are given up (reported, not measured): a relocalization onto a few frames' ground is
  // rarely possible and, on a repeated floor, easily a look-alike.
  const int to = addUnmeasuredMotion(failed);
  loop_closer_->abandonMap(graph_.poses());
  ever_lost_ = true;
  std::fill(measured_.begin(), measured_.end(), false);
  map_start_ = to;
}

const std::vector<RelocalizationAttempt>& Slam::relocalizationAttempts() const {
  static const std::vector<RelocalizationAttempt> none;
  return loop_closer_ ? loop_closer_->relocalizationAttempts() : none;
}

void Slam::relocalize(const Keyframe& current, FrameResult& result) {
  StageTimer timer;
  const std::vector<LoopCandidate> joined = loop_closer_->relocalize(current.index, current.features, graph_.poses());
  result.times.loop_ms += timer.lap();
  if (joined.empty()) return;
  addLocalizationEdges(joined, result);
  joinMap(result);
}

void Slam::addLocalizationEdges(const std::vector<LoopCandidate>& joined, FrameResult& result) {
  for (const LoopCandidate& candidate : joined) {
    report(reported(candidate));
    graph_.addEdge({candidate.frame_a, candidate.frame_b, candidate.T_a_b,
                    informationFrom(candidate.covariance, config_.graph.min_sigma_m, config_.graph.min_sigma_rad), true});
    ++result.loop_closures;
  }
}

void Slam::joinOrphanSegments(FrameResult& result) {
  orphans_due_ = false;
  StageTimer timer;
  const std::vector<LoopCandidate> joined = loop_closer_->joinOrphanSegments(graph_.poses());
  result.times.loop_ms += timer.lap();
  if (joined.empty()) return;
  addLocalizationEdges(joined, result);
  for (size_t i = 0; i < measured_.size(); ++i) {
    if (!measured_[i] && loop_closer_->segmentOf(static_cast<int>(i)) == kMapSegment) measured_[i] = true;
  }
  ++unoptimised_loops_;
  full_optimisation_due_ = true;
  optimise_now_ = true;
  optimiseIfDue(result, false);
}

void Slam::joinMap(FrameResult& result) {
  // The frames since the loss snap into place: the whole graph is optimised now.
  segment_ = kMapSegment;
  pending_search_.reset();
  for (size_t i = static_cast<size_t>(lost_since_); i < measured_.size(); ++i) measured_[i] = true;
  lost_ = false;
  orphans_due_ = true;
  result.status = FrameStatus::relocalized;
  ++unoptimised_loops_;
  full_optimisation_due_ = true;
  optimise_now_ = true;
}

void Slam::usePriorMap(const FeatureMap& prior) {
  if (!loop_closer_) throw std::invalid_argument("a prior map needs loop closure (loop_closure.enabled and a vocabulary)");
  if (!timestamps_.empty()) throw std::invalid_argument("a prior map must be given before the first frame");
  for (const MapAnchor& anchor : prior.anchors()) {
    graph_.addPose(anchor.T_map_anchor);
    timestamps_.push_back(std::nan(""));
    measured_.push_back(true);
  }
  loop_closer_->adoptPriorMap(prior);
  prior_frames_ = static_cast<int>(prior.anchors().size());
  segment_ = ++segments_started_;
  lost_ = true;
  lost_since_ = prior_frames_;
}

void Slam::closeLoopsOnPriorMap(const Keyframe& current, FrameResult& result) {
  if (current.index - last_prior_attempt_ < config_.localization.every_frames) return;
  last_prior_attempt_ = current.index;
  StageTimer timer;
  const auto candidate = loop_closer_->localizeOnPriorMap(current.index, current.features, graph_.poses(), prior_frames_);
  result.times.loop_ms += timer.lap();
  if (!candidate) return;
  graph_.addEdge({candidate->frame_a, candidate->frame_b, candidate->T_a_b,
                  informationFrom(candidate->covariance, config_.graph.min_sigma_m, config_.graph.min_sigma_rad), true});
  report(reported(*candidate));
  ++result.loop_closures;
  ++unoptimised_loops_;
}

void Slam::setCandidateObserver(std::function<void(const LoopCandidate&)> observer, bool keep) {
  candidate_observer_ = std::move(observer);
  keep_candidates_ = keep;
}

void Slam::report(const LoopCandidate& candidate) {
  if (candidate_observer_) candidate_observer_(candidate);
  if (keep_candidates_) candidates_.push_back(candidate);
}

LoopCandidate Slam::reported(LoopCandidate candidate) const {
  candidate.frame_a -= prior_frames_;
  candidate.frame_b -= prior_frames_;
  return candidate;
}

void Slam::closeLoops(const Keyframe& current, const TrackingImage& tracking, FrameResult& result) {
  if (!loop_closer_) return;
  StageTimer timer;
  for (LoopCandidate candidate : loop_closer_->process(current.index, segment_, current.features, graph_.poses())) {
    std::optional<LoopRays> pairs;
    if (candidate.accepted()) {
      pairs = measureLoopPairs(candidate, current, tracking);
    } else if (candidate.coarse_T_a_b) {
      pairs = rescueLoop(candidate, current, tracking);
      if (pairs) loop_closer_->loopRescued(candidate);
    }
    report(reported(candidate));
    if (!candidate.accepted()) continue;
    if (pairs) {
      pairs->edge = graph_.edges().size();
      loop_rays_.push_back(std::move(*pairs));
    }
    graph_.addEdge({candidate.frame_a, candidate.frame_b, candidate.T_a_b,
                    informationFrom(candidate.covariance, config_.graph.min_sigma_m, config_.graph.min_sigma_rad), true});
    if (mountFromLoops()) addLoopMountFactor(candidate, current);
    ++result.loop_closures;
    ++unoptimised_loops_;
    if (candidate.correction_m > config_.graph.full_optimisation_correction_m) full_optimisation_due_ = true;
  }
  result.times.loop_ms = timer.lap();
}

void Slam::optimiseIfDue(FrameResult& result, bool at_end) {
  const int frame = static_cast<int>(graph_.poses().size()) - 1;
  if (at_end) {
    if (unoptimised_loops_ == 0 && !window_solved_) return;
  } else if (!optimise_now_ && (unoptimised_loops_ == 0 || frame - last_optimised_frame_ < config_.graph.optimise_every_frames)) {
    return;
  }
  optimise_now_ = false;
  // Usually only the recent window moves, held to the fixed map by its loop edges: the cost stays flat. A
  // loop around a long path spreads its correction over the whole path, as does the end of the run.
  StageTimer timer;
  const int window = config_.graph.window_frames;
  const bool full = at_end || full_optimisation_due_ || window == 0 || frame < window;
  // The window reaches back to every loop edge added since the last optimisation.
  const int first_free = full ? 0 : std::max(0, std::min(frame + 1 - window, last_optimised_frame_ + 1));
  const int first_moving = std::max(first_free, prior_frames_);  // a prior map is held where it is
  graph_.optimise(first_moving);  // warm start: the current estimates are the initial values
  if (loop_closer_) loop_closer_->mapMoved(graph_.poses(), first_moving);
  window_solved_ = !full;
  full_optimisation_due_ = false;
  unoptimised_loops_ = 0;
  last_optimised_frame_ = frame;
  result.times.optimise_ms = timer.lap();
}

RigidEstimate Slam::fitMatches(const std::vector<Match>& matches, const Keyframe& previous, const Keyframe& current,
                              const FitSettings& settings, const std::optional<TransformPrior>& prior) const {
  const auto [previous_points, current_points] = matchedPoints(matches, current.features, previous.features);
  return fitRigidTransform(previous_points, current_points, settings, prior);
}

RigidEstimate Slam::refineMatches(const std::vector<Match>& matches, const Keyframe& previous, const Keyframe& current,
                                  const Pose2& initial) const {
  const auto [previous_points, current_points] = matchedPoints(matches, current.features, previous.features);
  return refineRigidTransform(previous_points, current_points, initial, odometry_fitting_);
}

std::optional<RigidEstimate> Slam::fitWithoutStill(const StillSplit& split, const Keyframe& previous, const Keyframe& current) const {
  if (split.still.empty() || split.moving.size() < static_cast<size_t>(config_.odometry.min_inliers)) return std::nullopt;
  RigidEstimate fit = fitMatches(split.moving, previous, current, odometry_fitting_);
  if (!fit.ok()) return std::nullopt;
  // Did the robot move? Then the still matches moved with the camera, not with the ground.
  double moved = 0.0;
  for (const Match& m : split.still) {
    const Eigen::Vector2d& p = current.features.points[static_cast<size_t>(m.query)];
    moved += (fit.T_target_source * p - p).norm();
  }
  moved /= static_cast<double>(split.still.size());
  if (moved < movedDistanceM()) return std::nullopt;
  return fit;
}

OdometryEdge Slam::estimateOdometry(const Keyframe& previous, const Keyframe& current, const PreparedFrame& prepared,
                                    FrameResult& result) {
  const std::optional<std::vector<Match>>& matched_ahead = prepared.matches_to_previous;
  StageTimer timer;
  RigidEstimate fit;
  std::vector<Match> matches;
  const double radius = config_.matching.guided_odometry_radius_m;
  if (radius > 0.0 && last_good_odometry_) {
    // Guided by constant velocity: compare only features the previous motion puts within `radius`.
    matches = matchNearby(current.features, previous.features, last_good_odometry_->T_prev_curr, radius, config_.matching.ratio);
    result.times.match_ms = timer.lap();
    fit = fitMatches(matches, previous, current, odometry_fitting_);
    result.times.fit_ms = timer.lap();
  }
  // Without a prediction, or when the robot changed its motion more than the radius allows: brute force.
  const bool guided_fit_kept =
      fit.ok() && fit.inliers >= config_.matching.guided_min_inlier_fraction * static_cast<double>(current.features.size());
  if (!guided_fit_kept && matched_ahead) {
    matches = *matched_ahead;  // the same brute-force matching, done on a preparing thread
  } else if (!guided_fit_kept) {
    matches = matcher_.match(current.features.descriptors, previous.features.descriptors);
    result.times.match_ms += timer.lap();
  }
  // Not in the paper: matches that stay still in the image while the others say the robot moved are the
  // robot's shadow, lens dirt or glare; fitted without them. Otherwise every match counts, except still
  // ones in cells known to hold artifacts (a moving robot whose ground matches are too few is not still).
  StillSplit split;
  if (config_.outdoor.reject_still) {
    split = splitStillMatches(matches, current.features, previous.features, config_.outdoor.still_radius_px / config_.camera.fx);
  } else {
    split.moving = matches;
  }
  std::vector<Match> used;
  if (const auto without_still = fitWithoutStill(split, previous, current)) {
    fit = *without_still;
    used = split.moving;
    result.still_matches = static_cast<int>(split.still.size());
    artifact_mask_.observe(current.features, split.still, split.moving);
  } else {
    used = artifact_mask_.withoutArtifacts(matches, current.features);
    // The guided fit already used exactly these matches: not fitted twice.
    if (!guided_fit_kept || used.size() != matches.size()) fit = fitMatches(used, previous, current, odometry_fitting_);
    if (fit.ok() && split.still.empty()) artifact_mask_.observe(current.features, {}, used);
    else artifact_mask_.fade();
  }
  result.times.fit_ms += timer.lap();
  result.matches = static_cast<int>(matches.size());
  result.inliers = fit.inliers;
  // Not in the paper: between images that do not overlap (a gap, a carried robot), a repetitive floor still
  // matches one repetition over; such a fit has rivals nearly as good and is not a motion.
  if (fit.ok() && fit.ambiguity() > config_.odometry_checks.max_ambiguity) fit.status = FitStatus::ambiguous;
  // Not in the paper: after a gap the true overlap can be too small to rival a repetition that matches well; a
  // motion unlike the robot's, at its speed over the time between the frames, is not a motion either.
  // Unless nearly every match agrees with it: then frames were dropped without a trace in the timestamps.
  const bool decisive = !used.empty() && fit.inliers >= config_.odometry_checks.decisive_inlier_share * static_cast<double>(used.size());
  if (fit.ok() && !decisive && !plausibleMotion(fit.T_target_source, previous.timestamp, current.timestamp)) {
    fit.status = FitStatus::implausible_motion;
  }
  // Not in the paper: on a floor that repeats (this fit or one of the last kRepeatedFloorFrames had a rival), a
  // motion unlike the robot's steps, or one a rival repetition is nearer to, is judged by them below: after a
  // gap two frames long the matches say the robot stepped back by a tile minus three steps, without a rival.
  if (!fit.rivals.empty()) last_rival_frame_ = current.index;
  // For bridges and the loop closer, a rival shows a repetition only with the inliers a fit needs: a weak floor's
  // failed fit of 5-11 inliers has rivals of 2-11 by chance (measured outdoors on sand and concrete photos), tiles'
  // rivals have 26-43. Odometry's own caution above stays with any rival.
  if (showsARepetition(fit, odometry_fitting_.min_inliers)) {
    last_repetition_frame_ = current.index;
    if (loop_closer_) loop_closer_->floorRepeats();  // without loop closure there is no global localization to tell
  }
  const bool repeated_floor = repeatedFloor(current.index);
  if (fit.ok() && repeated_floor && doubtedByTheSteps(fit, previous, current)) fit.status = FitStatus::implausible_motion;
  // Not in the paper: refused for its rivals or its speed on a repeated floor, the fit and its rivals are
  // judged by where the robot was going.
  std::optional<Pose2> likeliest_motion;
  if (fit.status == FitStatus::ambiguous || fit.status == FitStatus::implausible_motion) {
    StepsChoice by_steps = fitByMotion(fit, used, previous, current);
    if (by_steps.believed) {
      fit = std::move(*by_steps.believed);
      result.inliers = fit.inliers;
    }
    likeliest_motion = by_steps.likeliest;
  }

  // Too little evidence (not a motion refused for its rivals or its speed) where the overlap fell: a second look.
  const bool too_little = tooLittleEvidence(fit.status);
  const bool overlap_fell = last_good_odometry_ && static_cast<double>(result.matches) <=
                                                       config_.odometry_checks.low_overlap_max_match_share * last_good_odometry_->matches;
  if (too_little && overlap_fell) {
    if (auto second_look = fitLowOverlap(previous, current)) {
      result.inliers = second_look->first.inliers;
      return lowOverlapEdge(second_look->first, std::move(second_look->second), result.matches);
    }
  }
  // Still too little evidence (a smooth floor, mortar lines): the images themselves are aligned, believed only if
  // starts several steps on (frames dropped without a trace) end there too or explain the images far less well.
  // Not on a floor that repeats: the rival starts did not keep tiles from wrong loop closures (measured, seed 11's
  // outdoor tiles random walk: 0 -> 10). A repetition is shown by a rival with a fit's inliers: the few matches of a
  // failed fit on a faint floor have rivals by chance (on the seen OpenArena nki ground loop, every frame from its
  // 20th to its 42nd).
  if (too_little && !repetitionShown(current.index)) {
    if (auto aligned = odometryByAlignment(previous, current, prepared)) {
      aligned->matches = result.matches;
      return *aligned;
    }
  }
  // A fit on a few dozen keypoints is checked by aligning the images from its motion.
  const FitCheck check = fit.ok() ? checkedByAlignment(fit.T_target_source, fit.inliers, used, previous, current, prepared.alignment, repeated_floor)
                                  : FitCheck{};
  result.times.fit_ms += timer.lap();
  if (check.outcome == FitCheck::Outcome::replaced) {
    OdometryEdge replaced = alignedEdge(check.aligned_motion);
    replaced.matches = result.matches;
    return replaced;
  }
  OdometryEdge edge{fit.T_target_source, fit.covariance, result.matches, fit.inliers, fit.status, false, std::move(used),
                    fit.rms_residual_m};
  // Not in the paper: a fit of few inliers that the images aligned from its own motion could not confirm may be the
  // robot's own artifacts (on a faint floor's first frames, before anything showed them still: 12-15 inliers, 2-8
  // degrees off). The images aligned from the robot's usual steps, as where the features fail, replace it where they
  // end elsewhere (measured on the dev nki ground loop's first 130 frames: the run's heading 60 -> 16 degrees off).
  if (check.outcome == FitCheck::Outcome::unconfirmed && fit.inliers < config_.odometry_checks.align_confirm_below_inliers &&
      !repeated_floor) {
    if (auto aligned = odometryByAlignment(previous, current, prepared)) {
      const Pose2 apart = fit.T_target_source.inverse() * aligned->T_prev_curr;
      if (apart.translation().norm() > config_.odometry_checks.align_check_m || std::abs(apart.theta) > config_.odometry_checks.align_check_rad) {
        aligned->matches = result.matches;
        return *aligned;
      }
    }
  }
  // Few inliers the images did not confirm: the motion stands, less certain (as the images' own would be).
  if (check.outcome == FitCheck::Outcome::unconfirmed && fit.inliers < config_.odometry_checks.align_confirm_below_inliers) {
    edge.unconfirmed = true;
    edge.covariance += sigmaCovariance(config_.odometry_checks.align_sigma_m, config_.odometry_checks.align_sigma_rad);
    // Not in the paper: unless it says frames were dropped and most of its matches disagree (a repeated floor
    // fitted one repetition short of the gap): then the motion is not known.
    if (fewAgreeAcrossAGap(edge, previous, current)) {
      fit.status = edge.fit_status = FitStatus::ambiguous;
      edge.unconfirmed = false;
    }
  }
  return fit.ok() ? edge : fallbackOdometry(edge, measuredTurn(fit), likeliest_motion);
}

bool Slam::fewAgreeAcrossAGap(const OdometryEdge& edge, const Keyframe& previous, const Keyframe& current) const {
  const double min_share = config_.odometry_checks.unconfirmed_gap_min_inlier_share;
  if (!(min_share > 0.0) || edge.used.empty()) return false;
  const double share = static_cast<double>(edge.inliers) / static_cast<double>(edge.used.size());
  return share < min_share && spansGap(rockingSteps(edge, previous.timestamp, current.timestamp));
}

std::vector<Match> Slam::withoutRobotArtifacts(std::vector<Match> matches, const Keyframe& previous, const Keyframe& current) const {
  if (config_.outdoor.reject_still) {
    matches = splitStillMatches(matches, current.features, previous.features, config_.outdoor.still_radius_px / config_.camera.fx).moving;
  }
  return artifact_mask_.withoutArtifacts(matches, current.features);
}

std::optional<std::pair<RigidEstimate, std::vector<Match>>> Slam::fitLowOverlap(const Keyframe& previous, const Keyframe& current) const {
  // Not in the paper: at low overlap most of an image's features have no partner, and the ratio test also
  // throws away true matches whose second-best rival is close. A looser test keeps more of them; the fit is
  // believed only without a rival transform, which a repeated floor always has.
  const OdometryChecks& checks = config_.odometry_checks;
  if (!(checks.low_overlap_ratio > config_.matching.ratio)) return std::nullopt;
  std::vector<Match> matches = withoutRobotArtifacts(
      bruteForceMatch(current.features.descriptors, previous.features.descriptors, checks.low_overlap_ratio), previous, current);
  const RigidEstimate fit = fitMatches(matches, previous, current, odometry_fitting_);
  if (!fit.ok() || fit.ambiguity() > checks.low_overlap_max_ambiguity) return std::nullopt;
  return std::make_pair(fit, std::move(matches));
}

MotionPrior Slam::motionPrior(const Keyframe& previous, const Keyframe& current) const {
  const OdometryChecks& checks = config_.odometry_checks;
  int first_steps = 1, last_steps = checks.repetition_max_steps;
  if (last_good_odometry_seconds_ > 0.0 && current.timestamp > previous.timestamp) {
    // Timestamps that show how many frames are missing fix the steps (one for consecutive frames).
    const double ratio = (current.timestamp - previous.timestamp) / last_good_odometry_seconds_;
    if (ratio < 0.5 || ratio > 1.5) first_steps = last_steps = std::max(1, static_cast<int>(std::lround(ratio)));
  }
  MotionPriorSettings settings;
  settings.turn_doubt_rad = checks.repetition_turn_deg * M_PI / 180.0;
  settings.sigma_m = checks.repetition_sigma_m;
  settings.sigma_fraction = checks.repetition_sigma_fraction;
  settings.lever_m = calibrated_mount_.translation().z() * config_.outdoor.tilt_prior_deg * M_PI / 180.0;
  settings.step_turn_doubt_rad = checks.repetition_step_turn_deg * M_PI / 180.0;
  // A turn on the spot is a sharp turn (see sharpTurn): its lever arm exceeds sharp_turn_lever_m.
  const double chord = settings.lever_m > 0.0 ? checks.sharp_turn_lever_m / (2.0 * settings.lever_m) : 2.0;
  settings.spin_min_rad = chord < 1.0 ? 2.0 * std::asin(chord) : M_PI;
  settings.max_doubts = checks.repetition_max_doubts;
  settings.margin = checks.repetition_margin;
  settings.support_ratio = checks.repetition_support_ratio;
  return MotionPrior(usualSteps(), first_steps, last_steps, settings);
}

bool Slam::doubtedByTheSteps(const RigidEstimate& fit, const Keyframe& previous, const Keyframe& current) const {
  const OdometryChecks& checks = config_.odometry_checks;
  if (checks.repetition_max_steps <= 0 || !last_good_odometry_) return false;
  const MotionPrior prior = motionPrior(previous, current);
  const double off = prior.looseDoubtsOff(fit.T_target_source);
  if (!(off <= checks.repetition_margin * checks.repetition_max_doubts)) return true;
  return std::any_of(fit.rivals.begin(), fit.rivals.end(), [&](const Pose2& rival) { return prior.looseDoubtsOff(rival) < off; });
}

Slam::StepsChoice Slam::fitByMotion(const RigidEstimate& fit, const std::vector<Match>& used, const Keyframe& previous,
                                    const Keyframe& current) const {
  if (config_.odometry_checks.repetition_max_steps <= 0 || !last_good_odometry_) return {};
  const MotionPrior prior = motionPrior(previous, current);

  // The candidates: the fit, its rival repetitions, and what the matches say near each motion the robot can
  // have made (the true motion may have too little support to be found among all the matches). Each is refined
  // on its own matches: compared at its best, not at a RANSAC sample's guess.
  const auto [previous_points, current_points] = matchedPoints(used, current.features, previous.features);
  std::vector<RigidEstimate> candidates{fit};
  const auto add = [&](RigidEstimate estimate) {
    if (!estimate.ok()) return;
    for (const RigidEstimate& c : candidates) {
      if ((c.T_target_source.translation() - estimate.T_target_source.translation()).norm() < 0.005) return;  // the same one
    }
    candidates.push_back(std::move(estimate));
  };
  for (const Pose2& rival : fit.rivals) add(refineRigidTransform(previous_points, current_points, rival, odometry_fitting_));
  FitSettings near_settings = odometry_fitting_;
  near_settings.measure_ambiguity = false;
  for (const PredictedMotion& predicted : prior.predictions(fit.T_target_source.theta)) {
    std::vector<Eigen::Vector2d> near_previous, near_current;
    const double radius = 1.5 * predicted.sigma_m;
    for (size_t i = 0; i < current_points.size(); ++i) {
      if ((predicted.T_prev_curr * current_points[i] - previous_points[i]).norm() > radius) continue;
      near_previous.push_back(previous_points[i]);
      near_current.push_back(current_points[i]);
    }
    add(fitRigidTransform(near_previous, near_current, near_settings));
  }
  // Alone, the fit is believed only where the turn shows how many steps the gap spans (one number of steps
  // turns by its angle besides a single step): driving straight, a repetition is some number of steps on too.
  if (candidates.size() < 2 && prior.predictions(fit.T_target_source.theta).size() > 2) {
    if (!prior.likeliest({fit.T_target_source}, {fit.inliers})) return {};
    return {std::nullopt, fit.T_target_source};
  }
  // Each at its best on all the matches: its inliers are its support.
  std::vector<RigidEstimate> refined;
  std::vector<Pose2> motions;
  std::vector<int> support;
  for (const RigidEstimate& c : candidates) {
    refined.push_back(refineRigidTransform(previous_points, current_points, c.T_target_source, odometry_fitting_));
    motions.push_back(refined.back().ok() ? refined.back().T_target_source : c.T_target_source);
    support.push_back(refined.back().inliers);
  }
  const std::optional<size_t> chosen = prior.choose(motions, support);
  if (chosen && refined[*chosen].ok()) return {refined[*chosen], std::nullopt};
  // None believed: the best supported candidate the steps allow is the likeliest motion, a lost frame's guess
  // (measured on the seen outdoor sets' refused fits: within 5 mm of the truth for 63 of 106, the previous
  // motion 30; more than 3 mm further off than the previous motion for none).
  const std::optional<size_t> likeliest = prior.likeliest(motions, support);
  if (!likeliest) return {};
  return {std::nullopt, motions[*likeliest]};
}

std::vector<Pose2> Slam::usualSteps() const {
  if (steps_since_turn_ > 0 || !before_turn_) return {usualStep()};
  // Right after a turn on the spot: the steps go on as before in the camera's frame (the robot drives where it
  // now faces) or in the world's (the camera turned, the robot's path did not), turning as they turned.
  const auto& [before, turn] = *before_turn_;
  const double spun = wrapAngle(turn - before.theta);
  const Eigen::Vector2d turned = Eigen::Rotation2Dd(-spun) * before.translation();
  return {before, Pose2(turned.x(), turned.y(), before.theta)};
}

Pose2 Slam::usualStep() const {
  // The mean of the last good steps since the last sharp turn (each is a few millimetres off on a rocking
  // mount), or the last good one.
  Pose2 step = last_good_odometry_ ? last_good_odometry_->T_prev_curr : Pose2();
  const size_t averaged = std::min(recent_steps_.size(), steps_since_turn_);
  if (averaged == 0) return step;
  step = Pose2(0.0, 0.0, 0.0);
  for (auto recent = recent_steps_.end() - static_cast<std::ptrdiff_t>(averaged); recent != recent_steps_.end(); ++recent) {
    step.x += recent->x / static_cast<double>(averaged);
    step.y += recent->y / static_cast<double>(averaged);
    step.theta += recent->theta / static_cast<double>(averaged);
  }
  return step;
}

bool Slam::plausibleMotion(const Pose2& T_prev_curr, double previous_time, double current_time) const {
  if (!last_good_odometry_ || !(last_good_odometry_seconds_ > 0.0) || !(current_time > previous_time)) return true;
  const double scale = (current_time - previous_time) / last_good_odometry_seconds_;
  const Eigen::Vector2d predicted = scale * last_good_odometry_->T_prev_curr.translation();
  const OdometryChecks& checks = config_.odometry_checks;
  return (T_prev_curr.translation() - predicted).norm() <=
         checks.max_velocity_change_m + checks.max_velocity_change_fraction * predicted.norm();
}

bool Slam::mayBeARepetitionOff(const FrameResult& result) {
  // The recent frames' inliers, before this one joins them.
  std::array<int, kRecentSteps * 2> counts{};
  const auto end = std::copy(recent_inliers_.begin(), recent_inliers_.end(), counts.begin());
  if (result.inliers > 0) {
    recent_inliers_.push_back(result.inliers);
    if (recent_inliers_.size() > counts.size()) recent_inliers_.pop_front();
  }
  const double share = config_.odometry_checks.repeated_floor_unsure_inlier_share;
  if (!(share > 0.0) || result.status == FrameStatus::ok || end == counts.begin() || !floor_looks_repeated_) {
    return false;
  }
  const auto middle = counts.begin() + (end - counts.begin()) / 2;
  std::nth_element(counts.begin(), middle, end);
  return result.inliers < share * *middle;
}

bool Slam::spansGap(double steps) const {
  const double min_steps = config_.odometry_checks.gap_min_steps;
  return min_steps > 0.0 && steps >= min_steps;  // a lost frame's infinite steps too
}

bool Slam::vouchedFor(const OdometryEdge& odometry, const Keyframe& current) const {
  // Before the robot was seen moving, nothing has shown what stays still in the image: on a faint floor the robot's
  // own artifacts can outnumber the ground's keypoints and lock the fit at rest while it drives (docs/accuracy.md,
  // Session 28). A robot that really stands still at the start says `uncertain` until it moves.
  if (!seen_moving_ && !odometry.used.empty() && atRest(odometry.T_prev_curr, odometry.used, current)) return false;
  const OdometryChecks& checks = config_.odometry_checks;
  return checks.ok_sigmas <= 0.0 ||
         withinAtSigmas(odometry.covariance, checks.ok_sigmas, checks.ok_within_m, checks.ok_within_deg * M_PI / 180.0);
}

bool Slam::sharpTurn(const Pose2& T_prev_curr) const {
  const double lever_m = config_.odometry_checks.sharp_turn_lever_m;
  const double tilt_rad = config_.outdoor.tilt_prior_deg * M_PI / 180.0;
  const double height_m = calibrated_mount_.translation().z();
  return lever_m > 0.0 && 2.0 * std::abs(std::sin(0.5 * T_prev_curr.theta)) * height_m * tilt_rad > lever_m;
}

double Slam::rockingSteps(const OdometryEdge& odometry, double previous_time, double current_time) const {
  if (odometry.fallback) return std::numeric_limits<double>::infinity();  // the motion is unknown: so is the mount's
  if (!last_good_odometry_) return 1.0;
  double steps = 1.0;
  if (last_good_odometry_seconds_ > 0.0 && current_time > previous_time) {
    steps = std::max(steps, (current_time - previous_time) / last_good_odometry_seconds_);
  }
  // The median length of the last good motions: one of them off by millimetres (an online mount estimate
  // gone wrong; measured: a 6 mm motion amid 10 mm ones on the standard carpet lawnmower) does not make the
  // next one a gap. Only against a length long enough to measure (a robot standing still has no speed).
  if (recent_steps_.empty()) return steps;
  std::array<double, kRecentSteps> lengths{};  // no allocation per frame
  const auto end = std::transform(recent_steps_.begin(), recent_steps_.end(), lengths.begin(),
                                  [](const Pose2& step) { return step.translation().norm(); });
  const auto middle = lengths.begin() + (end - lengths.begin()) / 2;
  std::nth_element(lengths.begin(), middle, end);
  const double usual_m = *middle;
  if (usual_m > 4.0 * ground_sample_m_) steps = std::max(steps, odometry.T_prev_curr.translation().norm() / usual_m);
  return steps;
}

OdometryEdge Slam::fallbackOdometry(OdometryEdge failed, std::optional<double> turn, std::optional<Pose2> likeliest) const {
  // The paper's code assumes the previous motion again; its uncertainty grows by the fallback sigmas. A turn the
  // refused fit measured replaces the previous motion's; the likeliest of the refused fit's candidates, if any,
  // replaces both.
  failed.fallback = true;
  failed.T_prev_curr = Pose2();
  failed.covariance = Eigen::Matrix3d::Zero();
  if (last_good_odometry_) {
    failed.T_prev_curr = last_good_odometry_->T_prev_curr;
    failed.covariance = last_good_odometry_->covariance;
  }
  if (turn) failed.T_prev_curr = Pose2(failed.T_prev_curr.x, failed.T_prev_curr.y, *turn);
  failed.turn_measured = turn.has_value();
  if (likeliest && config_.fallback.likeliest_motion) {
    failed.T_prev_curr = *likeliest;
    failed.turn_measured = true;
  }
  failed.covariance += sigmaCovariance(config_.fallback.sigma_m, config_.fallback.sigma_rad);
  return failed;
}

Trajectory Slam::trajectory() const {
  Trajectory trajectory;
  for (size_t i = static_cast<size_t>(prior_frames_); i < graph_.poses().size(); ++i) {
    const Pose2 pose = i < mount_corrections_.size() ? graph_.poses()[i] * mount_corrections_[i] : graph_.poses()[i];
    trajectory.push_back({timestamps_[i], pose, measured_[i]});
  }
  return trajectory;
}

}  // namespace groundslam
