// Not in the paper: the run's first frames, given up where tracking was lost at once, measured again once the
// alignment knows the robot's step and what stays in the image.
//
// On a floor too faint for its keypoints (measured on the seen OpenArena nki ground rows and a dev sequence), the
// first frame or two cannot be measured: the alignment has no usual step to start from, nor a mean of recent heading
// images to take away what stays in the image (the robot's shadow edge, glare, dirt, bumper), so the images align
// back to rest and the keypoints' few matches are those artifacts. The map starts again after them (restartMap), but
// the first pose is the world frame's origin and the tables anchor every pose to it: the given-up motions' guesses
// (the previous motion, or a refused fit's likeliest, 2-11 degrees off there) turned the whole run. A few frames later
// both are known, and the images of those frames are kept until then.
#include "groundslam/pipeline/Slam.hpp"

namespace groundslam {

void Slam::keepEarlyImages(int frame, const PreparedFrame& prepared) {
  const OdometryChecks& checks = config_.odometry_checks;
  if (frame >= checks.restart_map_below_frames || !checks.measure_given_up_frames || !checks.align_images) return;
  // Copies: the frames' own pixels are moved on and may be reused in place.
  const auto copy = [](const AlignmentImage& image) { return AlignmentImage{image.pixels.clone(), image.scale, image.ground.clone()}; };
  early_images_.push_back({copy(prepared.alignment), copy(prepared.heading)});
}

void Slam::remeasureGivenUpFrames(int frame) {
  // Once the map can no longer start again, and is tracked from a usual step and a mean of the heading images.
  if (given_up_frames_measured_ || map_start_ == 0 || frame < config_.odometry_checks.restart_map_below_frames) return;
  if (lost_ || !last_good_odometry_ || heading_images_seen_ < kHeadingBackgroundImages) return;
  given_up_frames_measured_ = true;
  // From the map's first frame back: each motion measured joins one more frame to the map.
  for (int to = map_start_; to > 0 && static_cast<size_t>(to) < early_images_.size(); --to) {
    const int from = to - 1;
    const auto edge = odometryEdgeBetween(from, to);
    if (!edge) break;
    // A motion measured before the loss stands (the map gave its frames up, not their motions).
    if (graph_.edges()[*edge].information(2, 2) < kLeastMeasuredInformation) {
      const auto motion = alignedGivenUpMotion(from, to);
      if (!motion) break;
      graph_.remeasureEdge(*edge, motion->T_prev_curr, informationFrom(motion->covariance, config_.graph.min_sigma_m, config_.graph.min_sigma_rad));
      // The map hangs from frame `to`: it moves with it, rigidly.
      const Pose2 moved = graph_.poses()[static_cast<size_t>(from)] * motion->T_prev_curr;
      const Pose2 correction = moved * graph_.poses()[static_cast<size_t>(to)].inverse();
      for (size_t i = static_cast<size_t>(to); i < graph_.poses().size(); ++i) {
        graph_.setPose(static_cast<int>(i), correction * graph_.poses()[i]);
      }
      if (loop_closer_) loop_closer_->mapMoved(graph_.poses(), to);
    }
    measured_[static_cast<size_t>(from)] = true;
    map_start_ = from;
  }
  early_images_.clear();
  early_images_.shrink_to_fit();
}

std::optional<OdometryEdge> Slam::alignedGivenUpMotion(int from, int to) const {
  const EarlyImages &before = early_images_[static_cast<size_t>(from)], &now = early_images_[static_cast<size_t>(to)];
  for (const ImagePair& images : imagePairs(before.reduced, before.heading, now.reduced, now.heading)) {
    if (images.empty()) continue;
    const auto aligned = alignFromSteps(images, 1, true);
    if (!aligned) continue;
    const Pose2 T_prev_curr = groundMotionOf(aligned->W_previous_current);
    if (plausibleMotion(T_prev_curr, timestamps_[static_cast<size_t>(from)], timestamps_[static_cast<size_t>(to)]) &&
        movedTheRobot(T_prev_curr)) {
      return alignedEdge(T_prev_curr);
    }
  }
  return std::nullopt;
}

std::optional<size_t> Slam::odometryEdgeBetween(int from, int to) const {
  const std::vector<GraphEdge>& edges = graph_.edges();
  for (size_t i = 0; i < edges.size(); ++i) {
    if (edges[i].from == from && edges[i].to == to && !edges[i].loop) return i;
  }
  return std::nullopt;
}

}  // namespace groundslam
