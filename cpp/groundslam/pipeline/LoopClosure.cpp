#include "groundslam/pipeline/LoopClosure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <Eigen/Eigenvalues>

namespace groundslam {
namespace {

constexpr double kFootprintReachM = 0.15;  // a heading error moves features this far from the centre by angle * reach
constexpr double kMatchSlackM = 0.005;     // keypoint noise and the rocking mount
constexpr size_t kRecentLoops = 16;        // drift is bounded through any of these latest loop closures

/// How many of b's features the estimate T_a_b puts inside the bounding box of a's features grown by `margin_m`.
int featuresLandingOn(const GroundFeatures& a, const GroundFeatures& b, const Pose2& T_a_b, double margin_m) {
  if (a.size() == 0) return 0;
  Eigen::Vector2d lo = a.points.front(), hi = a.points.front();
  for (const Eigen::Vector2d& p : a.points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  lo.array() -= margin_m;
  hi.array() += margin_m;
  const Eigen::Matrix2d R = T_a_b.rotation();
  const Eigen::Vector2d t = T_a_b.translation();
  int landing = 0;
  for (const Eigen::Vector2d& p : b.points) {
    const Eigen::Vector2d q = R * p + t;
    if (q.x() >= lo.x() && q.x() <= hi.x() && q.y() >= lo.y() && q.y() <= hi.y()) ++landing;
  }
  return landing;
}

}  // namespace

const char* loopGateName(LoopGate gate) {
  switch (gate) {
    case LoopGate::none: return "";
    case LoopGate::bow_score: return "bow_score";
    case LoopGate::matches: return "matches";
    case LoopGate::covariance: return "covariance";
    case LoopGate::ambiguous: return "ambiguous";
    case LoopGate::still: return "still";
  }
  return "unknown";
}

const char* relocalizationOutcomeName(RelocalizationOutcome outcome) {
  switch (outcome) {
    case RelocalizationOutcome::joined: return "joined";
    case RelocalizationOutcome::pending: return "pending";
    case RelocalizationOutcome::on_a_keyframe: return "on_a_keyframe";
    case RelocalizationOutcome::not_localized: return "not_localized";
    case RelocalizationOutcome::joined_nearby: return "joined_nearby";
  }
  return "unknown";
}

LoopCloser::LoopCloser(const LoopClosureSettings& settings, std::shared_ptr<const Vocabulary> vocabulary,
                       const MatcherSettings& matching, const FitSettings& fitting, const LocalizationSettings& localization)
    : settings_(settings),
      localization_(localization),
      vocabulary_(std::move(vocabulary)),
      feature_map_(vocabulary_),
      matching_ratio_(matching.ratio),
      fitting_(fitting) {
  fitting_.measure_ambiguity = true;
  fitting_.min_inliers = settings.min_inliers;
  rejoin_fitting_ = fitting_;
  rejoin_fitting_.rival_max_rotation_rad = 1.0 * M_PI / 180.0;
}

std::vector<LoopCandidate> LoopCloser::process(int frame, int segment, const GroundFeatures& features,
                                               const std::vector<Pose2>& estimates) {
  segment_of_frame_.push_back(segment);
  BowVector bow = vocabulary_->transform(features.descriptors);
  const double step = frame > 0 ? (estimates[static_cast<size_t>(frame)].translation() -
                                   estimates[static_cast<size_t>(frame) - 1].translation()).norm()
                                : 0.0;
  path_length_m_.push_back((path_length_m_.empty() ? 0.0 : path_length_m_.back()) + step);
  unsure_motions_.push_back((unsure_motions_.empty() ? 0 : unsure_motions_.back()) + (next_motion_unsure_ ? 1 : 0));
  next_motion_unsure_ = false;
  std::vector<LoopCandidate> candidates;
  if (searchDue()) candidates = verifyCandidates(frame, features, bow, estimates);
  pending_.push_back({frame, features, std::move(bow)});
  admitPlaces(frame - settings_.database_delay_frames, estimates);
  return candidates;
}

void LoopCloser::forgetPendingFeatures(int frame, const std::vector<Eigen::Vector2d>& points) {
  const auto pending = std::find_if(pending_.begin(), pending_.end(), [&](const Pending& p) { return p.frame == frame; });
  if (pending == pending_.end() || points.empty()) return;
  GroundFeatures& features = pending->features;
  std::vector<bool> keep(features.size(), true);
  for (size_t i = 0; i < features.size(); ++i) {
    keep[i] = std::none_of(points.begin(), points.end(), [&](const Eigen::Vector2d& p) { return p == features.points[i]; });
  }
  features = selectFeatures(features, keep);
  pending->bow = vocabulary_->transform(features.descriptors);
}

bool LoopCloser::searchDue() const {
  // Loop closures a few millimetres apart constrain the same thing: the search rests until the robot has
  // driven loop_spacing_m since the last one, so a revisited place costs about what new ground costs.
  if (recent_loops_.empty()) return true;
  const double since_last = path_length_m_.back() - path_length_m_[static_cast<size_t>(recent_loops_.back().second)];
  return since_last >= settings_.loop_spacing_m;
}

std::vector<LoopCandidate> LoopCloser::verifyCandidates(int frame, const GroundFeatures& features, const BowVector& bow,
                                                        const std::vector<Pose2>& estimates) {
  std::vector<LoopCandidate> candidates;
  int accepted = 0;
  for (const BowMatch& match : selectCandidates(frame, bow, estimates)) {
    // More loop edges of one frame add little to its pose: verification stops at max_accepted_per_frame.
    if (accepted >= settings_.max_accepted_per_frame) break;
    if (unsure_motions_[static_cast<size_t>(frame)] > unsure_motions_[static_cast<size_t>(match.frame)]) {
      // Not in the paper: the map's estimate picks among a repeated floor's look-alike places, and across a motion
      // that may be a repetition off it may pick the wrong one (motionUnsure).
      LoopCandidate refused;
      refused.frame_a = match.frame;
      refused.frame_b = frame;
      refused.bow_score = match.score;
      refused.rejected_by = LoopGate::ambiguous;
      candidates.push_back(refused);
      continue;
    }
    const TransformPrior prior = priorOf(match.frame, frame, estimates);
    LoopCandidate candidate = verify(match.frame, places_.find(match.frame)->features(), frame, features, match.score, prior, fitting_);
    if (!std::isnan(candidate.covariance_score)) {
      candidate.correction_m = (candidate.T_a_b.translation() - prior.T_target_source.translation()).norm();
    }
    if (candidate.accepted()) {
      ++accepted;
      recent_loops_.emplace_back(candidate.frame_a, candidate.frame_b);
      if (recent_loops_.size() > kRecentLoops) recent_loops_.pop_front();
    }
    candidates.push_back(candidate);
  }
  return candidates;
}

void LoopCloser::trackingLost(const std::vector<Pose2>& estimates) {
  if (!pending_.empty()) admitPlaces(pending_.back().frame, estimates);
}

void LoopCloser::abandonMap(const std::vector<Pose2>& estimates) {
  trackingLost(estimates);
  for (int& segment : segment_of_frame_) {
    if (segment == kMapSegment) segment = kAbandonedSegment;
  }
  feature_map_.mergeSegment(kMapSegment, kAbandonedSegment);
  pending_localization_.reset();
  recent_loops_.clear();
}

void LoopCloser::admitPlaces(int last, const std::vector<Pose2>& estimates) {
  // The paper's delay: frame n-k may be found only from frame n on, so neighbours never close loops. It
  // becomes a place unless the map already covers its footprint; then only its pose is kept.
  while (!pending_.empty() && pending_.front().frame <= last) {
    Pending& entering = pending_.front();
    const Eigen::Vector2d position = estimates[static_cast<size_t>(entering.frame)].translation();
    if (!places_.covers(position, settings_.place_spacing_m)) {
      places_.add(entering.frame, position, entering.features, std::move(entering.bow));
      feature_map_.addAnchor(entering.frame, estimates[static_cast<size_t>(entering.frame)], segmentOf(entering.frame),
                             entering.features);
    }
    pending_.pop_front();
  }
}

std::vector<BowMatch> LoopCloser::selectCandidates(int frame, const BowVector& bow, const std::vector<Pose2>& estimates) const {
  // The nearest places whose footprint may overlap this one's, given the drift since the last correction,
  // ranked by BoW score; then the best of the whole map (the paper's global search), in case drift is larger.
  const Eigen::Vector2d here = estimates[static_cast<size_t>(frame)].translation();
  std::vector<BowMatch> nearby;
  for (const Place* place : places_.near(here, settings_.max_search_radius_m)) {
    if (static_cast<int>(nearby.size()) >= settings_.max_nearby_places) break;
    if (segmentOf(place->frame) != segmentOf(frame)) continue;  // drift across a tracking loss is unknown
    const double reach = settings_.search_radius_m + settings_.max_disagreement_m +
                         settings_.max_disagreement_per_m * driftPathLength(place->frame, frame);
    if ((place->position - here).norm() <= reach) nearby.push_back({place->frame, bowScore(bow, place->bow)});
  }
  const auto better = [](const BowMatch& x, const BowMatch& y) { return x.score > y.score || (x.score == y.score && x.frame < y.frame); };
  std::sort(nearby.begin(), nearby.end(), better);
  if (static_cast<int>(nearby.size()) > settings_.max_candidates) nearby.resize(static_cast<size_t>(settings_.max_candidates));
  const size_t wanted = static_cast<size_t>(settings_.max_candidates + settings_.max_global_candidates);
  if (settings_.max_global_candidates == 0) return nearby;
  for (const BowMatch& global : places_.query(bow, static_cast<int>(wanted))) {
    if (nearby.size() >= wanted) break;
    const bool chosen = std::any_of(nearby.begin(), nearby.end(), [&](const BowMatch& m) { return m.frame == global.frame; });
    if (!chosen && segmentOf(global.frame) == segmentOf(frame)) nearby.push_back(global);
  }
  return nearby;
}

double LoopCloser::driftPathLength(int frame_a, int frame_b) const {
  const auto s = [this](int frame) { return path_length_m_[static_cast<size_t>(frame)]; };
  double length = s(frame_b) - s(frame_a);
  for (const auto& [loop_a, loop_b] : recent_loops_) {
    // Through a recent loop closure: a -> its a, the closed loop (no drift), its b -> b.
    length = std::min(length, std::abs(s(frame_a) - s(loop_a)) + std::abs(s(frame_b) - s(loop_b)));
  }
  return length;
}

TransformPrior LoopCloser::priorOf(int frame_a, int frame_b, const std::vector<Pose2>& estimates) const {
  // Not in the paper: a loop transform far from what the map already believes is a lookalike place
  // (e.g. a tile offset), unless drift since the last correction could explain the difference.
  const double d = driftPathLength(frame_a, frame_b);
  return {between(estimates[static_cast<size_t>(frame_a)], estimates[static_cast<size_t>(frame_b)]),
          settings_.max_disagreement_m + settings_.max_disagreement_per_m * d,
          settings_.max_disagreement_rad + settings_.max_disagreement_rad_per_m * d};
}

LoopCandidate LoopCloser::verify(int frame_a, const GroundFeatures& a, int frame_b, const GroundFeatures& b,
                                 double bow_score, const TransformPrior& prior, const FitSettings& fitting) const {
  LoopCandidate candidate;
  candidate.frame_a = frame_a;
  candidate.frame_b = frame_b;
  candidate.bow_score = bow_score;
  // Gate 1: bag-of-words similarity.
  if (bow_score < settings_.min_bow_score) {
    candidate.rejected_by = LoopGate::bow_score;
    return candidate;
  }
  // Gate 2: keypoint matches (paper §III-B1 matching), guided by the map's estimate of T_a_b: only features
  // that the estimate, within its drift allowance, puts near each other are compared.
  const double search_m = prior.radius_m + kFootprintReachM * prior.radius_rad + kMatchSlackM;
  // Before comparing any descriptors: if fewer of b's features than the gate needs can land on a's
  // footprint at all, the footprints do not overlap enough (a microsecond, where matching takes milliseconds).
  if (featuresLandingOn(a, b, prior.T_target_source, search_m) < settings_.min_matches) {
    candidate.matches = 0;
    candidate.rejected_by = LoopGate::matches;
    return candidate;
  }
  const std::vector<Match> matches = matchNearby(b, a, prior.T_target_source, search_m, matching_ratio_);
  candidate.matches = static_cast<int>(matches.size());
  if (candidate.matches < settings_.min_matches) {
    candidate.rejected_by = LoopGate::matches;
    return candidate;
  }
  // Gate 3: the robust fit and its covariance score; a failed fit has unbounded covariance.
  std::vector<Eigen::Vector2d> points_a, points_b;
  for (const Match& m : matches) {
    points_a.push_back(a.points[static_cast<size_t>(m.train)]);
    points_b.push_back(b.points[static_cast<size_t>(m.query)]);
  }
  // Gate 3: RANSAC considers only transforms the map can still believe (see priorOf).
  const RigidEstimate fit = fitRigidTransform(points_a, points_b, fitting, prior);
  candidate.inliers = fit.inliers;
  candidate.covariance_score = fit.ok() ? fit.covarianceScore() : std::numeric_limits<double>::infinity();
  candidate.T_a_b = fit.T_target_source;
  candidate.covariance = fit.covariance;
  candidate.ambiguity = fit.ambiguity();
  if (candidate.covariance_score > settings_.max_covariance_score) {
    candidate.rejected_by = LoopGate::covariance;
    candidate.coarse_T_a_b = coarseTransform(fit, points_a, points_b, prior, fitting);
  } else if (candidate.ambiguity > settings_.max_ambiguity) {
    // Not in the paper: on a repetitive floor a transform shifted by one tile fits almost as well.
    candidate.rejected_by = LoopGate::ambiguous;
  } else if (onTheEarlierPose(candidate.T_a_b, localization_)) {
    // Not in the paper: the robot's shadow, lens dirt or bumper, left in both frames' features, match where they
    // stand in the image and put the robot back on the earlier pose; a true revisit lands there almost never
    // (measured over 108 outdoor and photo runs: the one accepted loop that close was 16 cm and 35° off the truth).
    candidate.rejected_by = LoopGate::still;
  }
  return candidate;
}

std::optional<Pose2> LoopCloser::coarseTransform(const RigidEstimate& fit, const std::vector<Eigen::Vector2d>& points_a,
                                                 const std::vector<Eigen::Vector2d>& points_b, const TransformPrior& prior,
                                                 FitSettings fitting) const {
  if (settings_.rescue_min_inliers <= 0 || fit.inliers < settings_.rescue_min_inliers) return std::nullopt;
  if (fit.ok()) {
    if (fit.ambiguity() > settings_.max_ambiguity || onTheEarlierPose(fit.T_target_source, localization_)) return std::nullopt;
    return fit.T_target_source;
  }
  // Too few inliers for the gate: the same consensus, fitted with the smaller count allowed.
  fitting.min_inliers = settings_.rescue_min_inliers;
  const RigidEstimate coarse = fitRigidTransform(points_a, points_b, fitting, prior);
  if (!coarse.ok() || coarse.ambiguity() > settings_.max_ambiguity || onTheEarlierPose(coarse.T_target_source, localization_)) return std::nullopt;
  return coarse.T_target_source;
}

void LoopCloser::loopRescued(const LoopCandidate& candidate) {
  recent_loops_.emplace_back(candidate.frame_a, candidate.frame_b);
  if (recent_loops_.size() > kRecentLoops) recent_loops_.pop_front();
}

void LoopCloser::mapMoved(const std::vector<Pose2>& estimates, int first_moved) {
  places_.moveFrom(first_moved, [&](int frame) { return estimates[static_cast<size_t>(frame)].translation(); });
  const auto& anchors = feature_map_.anchors();
  const auto first = std::partition_point(anchors.begin(), anchors.end(), [&](const MapAnchor& a) { return a.frame < first_moved; });
  for (auto anchor = first; anchor != anchors.end(); ++anchor) {
    const auto index = static_cast<int>(anchor - anchors.begin());
    feature_map_.moveAnchor(index, estimates[static_cast<size_t>(anchor->frame)]);
  }
}

LoopCandidate LoopCloser::candidateFrom(const Localization& localization, int frame) const {
  LoopCandidate candidate;
  candidate.frame_a = feature_map_.anchors()[static_cast<size_t>(localization.anchor)].frame;
  candidate.frame_b = frame;
  candidate.bow_score = std::nan("");
  candidate.matches = localization.votes;
  candidate.inliers = localization.inliers;
  candidate.T_a_b = localization.T_anchor_robot;
  candidate.covariance = localization.anchor_covariance;
  candidate.covariance_score = std::log10(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(localization.covariance).eigenvalues().maxCoeff());
  candidate.ambiguity = localization.inliers > 0 ? static_cast<double>(localization.runner_up_inliers) / localization.inliers : 1.0;
  candidate.rejected_by = LoopGate::none;
  return candidate;
}

void LoopCloser::adoptPriorMap(const FeatureMap& prior) {
  for (size_t a = 0; a < prior.anchors().size(); ++a) {
    feature_map_.addStoredAnchor({static_cast<int>(a), prior.anchors()[a].T_map_anchor, kMapSegment});
  }
  for (const MapFeature& f : prior.features()) feature_map_.addStoredFeature(f);
  segment_of_frame_.assign(prior.anchors().size(), kMapSegment);
  path_length_m_.assign(prior.anchors().size(), 0.0);
  unsure_motions_.assign(prior.anchors().size(), 0);
}

std::optional<LoopCandidate> LoopCloser::localizeOnPriorMap(int frame, const GroundFeatures& features,
                                                            const std::vector<Pose2>& estimates, int prior_frames) {
  AnchorFilter usable(feature_map_.anchors().size());
  for (size_t a = 0; a < usable.size(); ++a) usable[a] = feature_map_.anchors()[a].frame < prior_frames;
  const Localization localization = localizeOnMap(features, usable);
  if (!localization.ok() || onAnAnchorsPose(localization)) return std::nullopt;
  const size_t f = static_cast<size_t>(frame);
  const double d = recent_loops_.empty() ? path_length_m_[f] - path_length_m_[static_cast<size_t>(prior_frames)]
                                         : path_length_m_[f] - path_length_m_[static_cast<size_t>(recent_loops_.back().second)];
  const Pose2 disagreement = estimates[f].inverse() * localization.T_map_robot;
  if (disagreement.translation().norm() > settings_.max_disagreement_m + settings_.max_disagreement_per_m * d ||
      std::abs(disagreement.theta) > settings_.max_disagreement_rad + settings_.max_disagreement_rad_per_m * d) {
    return std::nullopt;
  }
  LoopCandidate candidate = candidateFrom(localization, frame);
  recent_loops_.emplace_back(candidate.frame_a, frame);
  if (recent_loops_.size() > kRecentLoops) recent_loops_.pop_front();
  return candidate;
}

Localization LoopCloser::localizeOnMap(const GroundFeatures& features, const AnchorFilter& usable) const {
  LocalizationSettings settings = localization_;
  if (floor_repeats_) settings.unrepeated_max_vote_ratio = settings.max_vote_ratio;
  return localizeGlobally(feature_map_, features, settings, fitting_, usable);
}

bool LoopCloser::onAnAnchorsPose(const Localization& localization) const {
  return onTheEarlierPose(localization.T_anchor_robot, localization_);
}

std::vector<LoopCandidate> LoopCloser::relocalize(int frame, const GroundFeatures& features, const std::vector<Pose2>& estimates) {
  const int lost_segment = segmentOf(frame);
  AnchorFilter usable(feature_map_.anchors().size());
  for (size_t a = 0; a < usable.size(); ++a) usable[a] = feature_map_.anchors()[a].segment == kMapSegment;
  const Localization localization = localizeOnMap(features, usable);
  const auto record = [&](RelocalizationOutcome outcome) { relocalization_attempts_.push_back({frame, localization, outcome}); };
  if (!localization.ok() || onAnAnchorsPose(localization)) {
    std::vector<LoopCandidate> nearby = rejoinNearby(frame, features, estimates);
    record(!nearby.empty()        ? RelocalizationOutcome::joined_nearby
           : localization.ok()    ? RelocalizationOutcome::on_a_keyframe
                                  : RelocalizationOutcome::not_localized);
    return nearby;
  }
  // One localization could be a lookalike; the next must agree with what odometry measured in between.
  PendingLocalization current{frame, localization, features};
  if (!pending_localization_ || segmentOf(pending_localization_->frame) != lost_segment ||
      !agreeWithOdometry(*pending_localization_, current, estimates)) {
    pending_localization_ = std::move(current);
    record(RelocalizationOutcome::pending);
    return {};
  }
  // Agreeing, but too near on a repeating floor: the earlier waits for a frame further on to confirm it.
  if (!farEnoughApart(pending_localization_->frame, frame, estimates)) {
    record(RelocalizationOutcome::pending);
    return {};
  }
  const PendingLocalization earlier = std::move(*pending_localization_);
  pending_localization_.reset();
  joinSegments(lost_segment, kMapSegment);
  std::vector<LoopCandidate> joined = {edgeOf(earlier), edgeOf(current)};
  recent_loops_.emplace_back(joined.back().frame_a, frame);
  if (recent_loops_.size() > kRecentLoops) recent_loops_.pop_front();
  record(RelocalizationOutcome::joined);
  return joined;
}

bool LoopCloser::lostFromTheMap(int segment) const {
  const auto first = std::find(segment_of_frame_.begin(), segment_of_frame_.end(), segment);
  return first != segment_of_frame_.begin() && first != segment_of_frame_.end() && *(first - 1) == kMapSegment;
}

std::vector<LoopCandidate> LoopCloser::rejoinNearby(int frame, const GroundFeatures& features, const std::vector<Pose2>& estimates) {
  // On a floor that repeats, a repetition lies within the reach of a few dropped frames; there only global
  // localization, which compares every repetition, may join the segment. So does a segment lost again before it was
  // found: two unknown motions lie between it and the map.
  const int lost_segment = segmentOf(frame);
  if (!(settings_.lost_reach_m > 0.0) || floor_repeats_ || pending_.empty() || pending_.back().frame != frame ||
      !lostFromTheMap(lost_segment)) {
    return {};
  }
  // The nearest places first, not the best BoW scores: where the robot was lost (a weak floor, the robot's own
  // shadow) the scores hardly differ, and the estimate is off by a few steps only.
  const Eigen::Vector2d here = estimates[static_cast<size_t>(frame)].translation();
  std::vector<BowMatch> nearby;
  for (const Place* place : places_.near(here, settings_.max_search_radius_m + settings_.lost_reach_m)) {
    if (static_cast<int>(nearby.size()) >= 2 * settings_.max_candidates) break;
    if (segmentOf(place->frame) != kMapSegment) continue;
    const double reach = settings_.search_radius_m + settings_.lost_reach_m + settings_.max_disagreement_m +
                         settings_.max_disagreement_per_m * driftPathLength(place->frame, frame);
    if ((place->position - here).norm() <= reach) nearby.push_back({place->frame, bowScore(pending_.back().bow, place->bow)});
  }
  for (const BowMatch& match : nearby) {
    TransformPrior prior = priorOf(match.frame, frame, estimates);
    prior.radius_m += settings_.lost_reach_m;
    prior.radius_rad += settings_.lost_reach_deg * M_PI / 180.0;
    LoopCandidate candidate = verify(match.frame, places_.find(match.frame)->features(), frame, features, match.score, prior, rejoin_fitting_);
    if (!candidate.accepted()) continue;
    candidate.correction_m = (candidate.T_a_b.translation() - prior.T_target_source.translation()).norm();
    // As for a global localization: the next accepted one must agree with what odometry measured in between.
    const std::optional<LoopCandidate> earlier = pending_rejoin_;
    pending_rejoin_ = candidate;
    if (!earlier || segmentOf(earlier->frame_b) != lost_segment) return {};
    const auto placed = [&](const LoopCandidate& c) {
      PendingLocalization p{c.frame_b, {}, {}};
      p.localization.T_map_robot = estimates[static_cast<size_t>(c.frame_a)] * c.T_a_b;
      return p;
    };
    if (!agreeWithOdometry(placed(*earlier), placed(candidate), estimates)) return {};
    pending_rejoin_.reset();
    joinSegments(lost_segment, kMapSegment);
    recent_loops_.emplace_back(candidate.frame_a, frame);
    if (recent_loops_.size() > kRecentLoops) recent_loops_.pop_front();
    return {*earlier, candidate};
  }
  return {};
}

std::vector<LoopCandidate> LoopCloser::joinOrphanSegments(const std::vector<Pose2>& estimates) {
  // Localizing costs a few milliseconds a keyframe: a segment tries at most this many, spread over its frames.
  constexpr size_t kMaxAnchorsTried = 8;
  const std::vector<MapAnchor>& anchors = feature_map_.anchors();
  std::map<int, std::vector<int>> anchors_of_segment;
  for (size_t a = 0; a < anchors.size(); ++a) {
    if (anchors[a].segment > kMapSegment) anchors_of_segment[anchors[a].segment].push_back(static_cast<int>(a));
  }
  std::vector<LoopCandidate> joined;
  for (const auto& [segment, members] : anchors_of_segment) {
    if (members.size() < 2) continue;  // one localization cannot be confirmed
    AnchorFilter usable(anchors.size());
    for (size_t a = 0; a < usable.size(); ++a) usable[a] = anchors[a].segment == kMapSegment;
    std::vector<PendingLocalization> found;
    const size_t tried = std::min(kMaxAnchorsTried, members.size());
    for (size_t k = 0; k < tried; ++k) {
      const int anchor = members[k * (members.size() - 1) / (tried - 1)];
      const int frame = anchors[static_cast<size_t>(anchor)].frame;
      GroundFeatures seen = feature_map_.featuresInAnchorFrame(anchor);
      const Localization localization = localizeOnMap(seen, usable);
      if (!localization.ok() || onAnAnchorsPose(localization)) continue;
      const PendingLocalization current{frame, localization, std::move(seen)};
      const auto agreeing = std::find_if(found.begin(), found.end(), [&](const PendingLocalization& earlier) {
        return agreeWithOdometry(earlier, current, estimates) && farEnoughApart(earlier.frame, frame, estimates);
      });
      if (agreeing == found.end()) {
        found.push_back(current);
        continue;
      }
      joined.push_back(edgeOf(*agreeing));
      joined.push_back(edgeOf(current));
      joinSegments(segment, kMapSegment);
      break;
    }
  }
  return joined;
}

bool LoopCloser::agreeWithOdometry(const PendingLocalization& a, const PendingLocalization& b,
                                   const std::vector<Pose2>& estimates) const {
  const Pose2 by_localization = between(a.localization.T_map_robot, b.localization.T_map_robot);
  const Pose2 by_odometry = between(estimates[static_cast<size_t>(a.frame)], estimates[static_cast<size_t>(b.frame)]);
  const Pose2 disagreement = by_odometry.inverse() * by_localization;
  return disagreement.translation().norm() <= localization_.max_odometry_disagreement_m &&
         std::abs(disagreement.theta) <= localization_.max_odometry_disagreement_rad;
}

bool LoopCloser::farEnoughApart(int frame_a, int frame_b, const std::vector<Pose2>& estimates) const {
  const double baseline = localization_.repeated_floor_baseline_m;
  if (!floor_repeats_ || baseline <= 0.0) return true;
  return between(estimates[static_cast<size_t>(frame_a)], estimates[static_cast<size_t>(frame_b)]).translation().norm() >= baseline;
}

LoopCandidate LoopCloser::edgeOf(const PendingLocalization& found) const {
  // Twice the tolerance two localizations must agree within: how far the map's bending may put the pose off one
  // keyframe's own view of it.
  constexpr double kKeyframeReach = 2.0;
  LoopCandidate candidate = candidateFrom(found.localization, found.frame);
  const Place* place = localization_.measure_on_keyframe ? places_.find(candidate.frame_a) : nullptr;
  if (place == nullptr || found.features.size() == 0) return candidate;  // a prior map's keyframes have no places
  const TransformPrior around{candidate.T_a_b, kKeyframeReach * localization_.max_odometry_disagreement_m,
                              kKeyframeReach * localization_.max_odometry_disagreement_rad};
  // No BoW gate: the localization found the place (and, as a localization, the edge reports no BoW score).
  LoopCandidate measured = verify(candidate.frame_a, place->features(), found.frame, found.features,
                                  std::numeric_limits<double>::infinity(), around, fitting_);
  if (!measured.accepted()) return candidate;
  measured.bow_score = candidate.bow_score;
  return measured;
}

void LoopCloser::joinSegments(int from, int to) {
  for (int& s : segment_of_frame_) {
    if (s == from) s = to;
  }
  feature_map_.mergeSegment(from, to);
}

}  // namespace groundslam
