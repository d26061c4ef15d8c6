#include "groundslam/eval/TrajectoryMetrics.hpp"

#include "groundslam/eval/NumberText.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <Eigen/Geometry>

namespace groundslam {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

struct PosePair {
  double timestamp;
  Pose2 first;   ///< ground truth
  Pose2 second;  ///< estimate
  bool measured;  ///< the estimate was measured, not assumed
};

/// Pairs of (ground truth, estimate) with matching timestamps; both inputs in any order.
std::vector<PosePair> pairByTime(Trajectory groundtruth, Trajectory estimate, double max_dt) {
  auto by_time = [](const StampedPose& a, const StampedPose& b) { return a.timestamp < b.timestamp; };
  std::sort(groundtruth.begin(), groundtruth.end(), by_time);
  std::sort(estimate.begin(), estimate.end(), by_time);
  std::vector<PosePair> pairs;
  size_t j = 0;
  for (const auto& gt : groundtruth) {
    while (j + 1 < estimate.size() && estimate[j + 1].timestamp <= gt.timestamp) ++j;
    // The nearest estimate is estimate[j] or estimate[j + 1].
    size_t best = j;
    if (j + 1 < estimate.size() &&
        std::abs(estimate[j + 1].timestamp - gt.timestamp) < std::abs(estimate[j].timestamp - gt.timestamp)) {
      best = j + 1;
    }
    if (!estimate.empty() && std::abs(estimate[best].timestamp - gt.timestamp) <= max_dt) {
      pairs.push_back({gt.timestamp, gt.T_world_robot, estimate[best].T_world_robot, estimate[best].measured});
    }
  }
  return pairs;
}

double rms(const std::vector<double>& values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0.0;
  for (double v : values) sum += v * v;
  return std::sqrt(sum / static_cast<double>(values.size()));
}

}  // namespace

Pose2 alignSE2(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to) {
  if (from.empty()) return Pose2();
  Eigen::Vector2d mean_from = Eigen::Vector2d::Zero(), mean_to = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < from.size(); ++i) mean_from += from[i], mean_to += to[i];
  mean_from /= static_cast<double>(from.size());
  mean_to /= static_cast<double>(from.size());
  // Maximise sum b_i . R a_i = cos(t) sum(a . b) + sin(t) sum(a x b): a proper rotation by construction.
  double dot = 0.0, cross = 0.0;
  for (size_t i = 0; i < from.size(); ++i) {
    const Eigen::Vector2d a = from[i] - mean_from, b = to[i] - mean_to;
    dot += a.dot(b);
    cross += a.x() * b.y() - a.y() * b.x();
  }
  const double theta = std::atan2(cross, dot);
  const Eigen::Vector2d t = mean_to - Eigen::Rotation2Dd(theta) * mean_from;
  return Pose2(t.x(), t.y(), theta);
}

TrajectoryEvaluation evaluateTrajectory(const Trajectory& groundtruth, const Trajectory& estimate, double max_time_difference) {
  TrajectoryEvaluation result;
  TrajectoryMetrics& m = result.metrics;
  const auto pairs = pairByTime(groundtruth, estimate, max_time_difference);
  m.groundtruth_frames = static_cast<int>(groundtruth.size());
  m.paired_frames = static_cast<int>(pairs.size());
  m.fraction_estimated = groundtruth.empty() ? 0.0 : static_cast<double>(pairs.size()) / static_cast<double>(groundtruth.size());
  m.measured_frames = static_cast<int>(std::count_if(pairs.begin(), pairs.end(), [](const PosePair& p) { return p.measured; }));
  m.fraction_measured = groundtruth.empty() ? 0.0 : static_cast<double>(m.measured_frames) / static_cast<double>(groundtruth.size());
  if (pairs.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    m.translation_mae_m = m.translation_mae_cm_per_m = m.rotation_mae_deg = m.ate_rmse_m = nan;
    m.rpe_translation_rmse_m = m.rpe_rotation_rmse_deg = nan;
    return result;
  }

  // The paper anchors the first estimated pose to the first ground-truth pose.
  const Pose2 T_gt_est = pairs.front().first * pairs.front().second.inverse();
  double sum_t = 0.0, sum_r = 0.0;
  std::vector<Eigen::Vector2d> estimated_positions, true_positions;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const Pose2& gt = pairs[i].first;
    const Pose2 anchored = T_gt_est * pairs[i].second;
    const double e_t = (anchored.translation() - gt.translation()).norm();
    const double e_r = std::abs(wrapAngle(anchored.theta - gt.theta)) * kRadToDeg;
    sum_t += e_t;
    sum_r += e_r;
    result.frame_errors.push_back({pairs[i].timestamp, e_t, e_r});
    if (i > 0) m.path_length_m += (gt.translation() - pairs[i - 1].first.translation()).norm();
    estimated_positions.push_back(pairs[i].second.translation());
    true_positions.push_back(gt.translation());
  }
  m.translation_mae_m = sum_t / static_cast<double>(pairs.size());
  m.rotation_mae_deg = sum_r / static_cast<double>(pairs.size());
  m.translation_mae_cm_per_m = m.path_length_m > 0.0 ? 100.0 * m.translation_mae_m / m.path_length_m
                                                     : std::numeric_limits<double>::quiet_NaN();

  const Pose2 T_align = alignSE2(estimated_positions, true_positions);
  std::vector<double> ate, rpe_t, rpe_r;
  for (size_t i = 0; i < pairs.size(); ++i) {
    ate.push_back((T_align * estimated_positions[i] - true_positions[i]).norm());
    if (i == 0) continue;
    const Pose2 true_motion = between(pairs[i - 1].first, pairs[i].first);
    const Pose2 estimated_motion = between(pairs[i - 1].second, pairs[i].second);
    const Pose2 error = true_motion.inverse() * estimated_motion;
    rpe_t.push_back(error.translation().norm());
    rpe_r.push_back(std::abs(error.theta) * kRadToDeg);
  }
  m.ate_rmse_m = rms(ate);
  m.rpe_translation_rmse_m = rms(rpe_t);
  m.rpe_rotation_rmse_deg = rms(rpe_r);
  return result;
}

std::string metricsToJson(const TrajectoryMetrics& m) {
  std::string json = "{\n";
  const auto field = [&](const char* name, const std::string& value, bool last = false) {
    json += std::string("  \"") + name + "\": " + value + (last ? "\n" : ",\n");
  };
  field("groundtruth_frames", std::to_string(m.groundtruth_frames));
  field("paired_frames", std::to_string(m.paired_frames));
  field("fraction_estimated", jsonNumber(m.fraction_estimated, 6));
  field("measured_frames", std::to_string(m.measured_frames));
  field("fraction_measured", jsonNumber(m.fraction_measured, 6));
  field("path_length_m", jsonNumber(m.path_length_m, 6));
  field("translation_mae_m", jsonNumber(m.translation_mae_m, 9));
  field("translation_mae_cm_per_m", jsonNumber(m.translation_mae_cm_per_m, 6));
  field("rotation_mae_deg", jsonNumber(m.rotation_mae_deg, 6));
  field("ate_rmse_m", jsonNumber(m.ate_rmse_m, 9));
  field("rpe_translation_rmse_m", jsonNumber(m.rpe_translation_rmse_m, 9));
  field("rpe_rotation_rmse_deg", jsonNumber(m.rpe_rotation_rmse_deg, 6), true);
  return json + "}\n";
}

std::string metricsToText(const TrajectoryMetrics& m) {
  char coverage[256];
  std::snprintf(coverage, sizeof(coverage),
                "frames measured       %d / %d (%.1f%%; %d more with a pose assumed from earlier motion)\n",
                m.measured_frames, m.groundtruth_frames, 100.0 * m.fraction_measured, m.paired_frames - m.measured_frames);
  return std::string(coverage) + "path length           " + textNumber(m.path_length_m, 3) + " m\n" +
         "translational MAE     " + textNumber(m.translation_mae_cm_per_m, 3) + " cm/m  (" +
         textNumber(m.translation_mae_m, 2, 1000.0) + " mm, first pose anchored)\n" +
         "rotational MAE        " + textNumber(m.rotation_mae_deg, 3) + " deg\n" +
         "ATE RMSE (SE2-aligned) " + textNumber(m.ate_rmse_m, 2, 1000.0) + " mm\n" +
         "RPE RMSE (per frame)  " + textNumber(m.rpe_translation_rmse_m, 3, 1000.0) + " mm, " +
         textNumber(m.rpe_rotation_rmse_deg, 4) + " deg\n";
}

}  // namespace groundslam
