#pragma once
// An SE(2) pose graph solved with Ceres by Levenberg-Marquardt (paper §III-C). Each edge carries the
// information (inverse covariance) of the fit that measured it; loop edges get a robust loss so that
// one wrong loop closure cannot bend the map.

#include <vector>

#include <Eigen/Core>

#include "groundslam/core/Pose2.hpp"

namespace groundslam {

struct GraphEdge {
  int from = 0;
  int to = 0;
  Pose2 T_from_to;                  ///< measured pose of `to` in the frame of `from`
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();  ///< inverse covariance of (x, y, theta)
  bool loop = false;                ///< loop closure (robust loss) or odometry
};

struct PoseGraphSettings {
  double loop_loss_scale = 1.0;  ///< Cauchy scale on a loop edge's whitened residual (in standard deviations)
  int max_iterations = 50;       ///< Levenberg-Marquardt iterations per optimisation
};

struct OptimisationSummary {
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
};

class PoseGraph {
 public:
  explicit PoseGraph(const PoseGraphSettings& settings = {});

  /// Adds a pose with its initial estimate; returns its index. Pose 0 is held fixed (it defines the map frame).
  int addPose(const Pose2& initial_T_world_robot);
  void addEdge(const GraphEdge& edge);
  /// Optimises all poses, starting from the current estimates.
  OptimisationSummary optimise() { return optimise(0); }
  /// Optimises poses first_free..last only, holding the earlier ones that edges tie them to fixed: the
  /// cost depends on the window, not on the size of the graph (when edges arrive in the order of their
  /// later pose, as a SLAM front end adds them).
  OptimisationSummary optimise(int first_free);

  const std::vector<Pose2>& poses() const { return poses_; }
  const std::vector<GraphEdge>& edges() const { return edges_; }
  void setPose(int index, const Pose2& T_world_robot) { poses_[static_cast<size_t>(index)] = T_world_robot; }
  /// A new measurement and information for edge `index` (same poses: a measurement made again, more precisely).
  void remeasureEdge(size_t index, const Pose2& T_from_to, const Eigen::Matrix3d& information) {
    edges_[index].T_from_to = T_from_to;
    edges_[index].information = information;
  }

 private:
  PoseGraphSettings settings_;
  std::vector<Pose2> poses_;
  std::vector<GraphEdge> edges_;
  bool edges_in_pose_order_ = true;  ///< max(from, to) never decreases along edges_
};

/// diag(sigma_m^2, sigma_m^2, sigma_rad^2): the covariance of independent x, y and heading errors.
Eigen::Matrix3d sigmaCovariance(double sigma_m, double sigma_rad);

/// Information matrix from a covariance, with a floor on the standard deviations (unmodelled errors).
Eigen::Matrix3d informationFrom(const Eigen::Matrix3d& covariance, double min_sigma_m, double min_sigma_rad);

}  // namespace groundslam
