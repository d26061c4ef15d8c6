#include "groundslam/io/RunFiles.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/TextParsing.hpp"

namespace groundslam {

std::string formatLoopClosuresCsv(const std::vector<LoopCandidate>& candidates) {
  std::string csv = "frame_a,frame_b,x,y,theta,bow_score,matches,covariance_score\n";
  char row[256];
  for (const auto& c : candidates) {
    if (!c.accepted()) continue;
    std::snprintf(row, sizeof(row), "%d,%d,%.9f,%.9f,%.9f,%.6f,%d,%.4f\n", c.frame_a, c.frame_b, c.T_a_b.x, c.T_a_b.y,
                  c.T_a_b.theta, c.bow_score, c.matches, c.covariance_score);
    csv += row;
  }
  return csv;
}

std::string formatRelocalizationsCsv(const std::vector<RelocalizationAttempt>& attempts) {
  std::string csv = "frame,status,outcome,x,y,theta,votes,runner_up_votes,inliers,strong_inliers,runner_up_inliers\n";
  char row[256];
  for (const RelocalizationAttempt& a : attempts) {
    const Localization& l = a.localization;
    csv += std::to_string(a.frame) + "," + localizationStatusName(l.status) + "," + relocalizationOutcomeName(a.outcome);
    if (l.status == LocalizationStatus::too_few_votes) {
      csv += ",,,";
    } else {
      std::snprintf(row, sizeof(row), ",%.9f,%.9f,%.9f", l.T_map_robot.x, l.T_map_robot.y, l.T_map_robot.theta);
      csv += row;
    }
    std::snprintf(row, sizeof(row), ",%d,%d,%d,%d,%d\n", l.votes, l.runner_up_votes, l.inliers, l.strong_inliers, l.runner_up_inliers);
    csv += row;
  }
  return csv;
}

std::string formatCandidatesCsv(const std::vector<LoopCandidate>& candidates,
                                const std::vector<std::optional<CandidateTruth>>& truths) {
  const bool with_truth = !truths.empty();
  std::string csv = "frame_a,frame_b,bow_score,matches,inliers,covariance_score,rejected_by,accepted,x,y,theta,ambiguity";
  csv += with_truth ? ",true_distance_m,footprints_overlap,translation_error_m,rotation_error_deg\n" : "\n";
  char row[512];
  for (size_t i = 0; i < candidates.size(); ++i) {
    const LoopCandidate& c = candidates[i];
    // A candidate never fitted (rejected before, by the BoW score or the matches) has no transform, no
    // covariance score and no ambiguity: those fields stay empty.
    const bool fitted = std::isfinite(c.covariance_score);
    std::snprintf(row, sizeof(row), "%d,%d,%.6f,%d,%d,", c.frame_a, c.frame_b, c.bow_score, c.matches, c.inliers);
    csv += row;
    if (fitted) {
      std::snprintf(row, sizeof(row), "%.4f", c.covariance_score);
      csv += row;
    }
    std::snprintf(row, sizeof(row), ",%s,%d,", c.accepted() ? "none" : loopGateName(c.rejected_by), c.accepted() ? 1 : 0);
    csv += row;
    if (fitted) {
      std::snprintf(row, sizeof(row), "%.9f,%.9f,%.9f,%.4f", c.T_a_b.x, c.T_a_b.y, c.T_a_b.theta, c.ambiguity);
      csv += row;
    } else {
      csv += ",,,";
    }
    if (with_truth) {
      if (truths[i]) {
        std::snprintf(row, sizeof(row), ",%.6f,%d,%.9f,%.6f", truths[i]->distance_m, truths[i]->footprints_overlap ? 1 : 0,
                      truths[i]->translation_error_m, truths[i]->rotation_error_deg);
        csv += row;
      } else {
        csv += ",,,,";
      }
    }
    csv += "\n";
  }
  return csv;
}

std::vector<LoopCandidate> readCandidatesCsv(const std::string& path) {
  std::istringstream in(readTextFile(path));
  std::string line;
  if (!std::getline(in, line) || line.rfind("frame_a,frame_b,bow_score", 0) != 0) {
    throw InputError(path + ":1: not a candidates.csv header");
  }
  std::vector<LoopCandidate> candidates;
  for (int number = 2; std::getline(in, line); ++number) {
    if (trim(line).empty()) continue;
    const std::vector<std::string> cells = splitCsvRow(line);
    if (cells.size() < 12) throw InputError(path + ":" + std::to_string(number) + ": expected at least 12 columns");
    try {
      LoopCandidate c;
      c.frame_a = std::stoi(cells[0]);
      c.frame_b = std::stoi(cells[1]);
      c.bow_score = std::stod(cells[2]);
      c.matches = std::stoi(cells[3]);
      c.inliers = std::stoi(cells[4]);
      // Empty for a candidate never fitted: no covariance score, transform or ambiguity.
      const auto numberOrNan = [](const std::string& cell) { return trim(cell).empty() ? std::nan("") : std::stod(cell); };
      c.covariance_score = numberOrNan(cells[5]);
      static const std::map<std::string, LoopGate> gates = {{"none", LoopGate::none}, {"bow_score", LoopGate::bow_score},
                                                             {"matches", LoopGate::matches}, {"covariance", LoopGate::covariance},
                                                             {"ambiguous", LoopGate::ambiguous}, {"still", LoopGate::still}};
      const auto gate = gates.find(cells[6]);
      if (gate == gates.end()) throw InputError(path + ":" + std::to_string(number) + ": unknown gate '" + cells[6] + "'");
      c.rejected_by = gate->second;
      if (std::isfinite(c.covariance_score) || !trim(cells[8]).empty()) {
        c.T_a_b = Pose2(std::stod(cells[8]), std::stod(cells[9]), std::stod(cells[10]));
      }
      c.ambiguity = numberOrNan(cells[11]);
      candidates.push_back(c);
    } catch (const std::logic_error&) {
      throw InputError(path + ":" + std::to_string(number) + ": not a number in the row");
    }
  }
  return candidates;
}

void markUnmeasuredPoses(const std::string& path, Trajectory& trajectory) {
  std::istringstream in(readTextFile(path));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header = splitCsvRow(line);
  for (std::string& cell : header) cell = trim(cell);
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw InputError(path + ":1: no '" + name + "' column");
    return static_cast<size_t>(it - header.begin());
  };
  const size_t time_column = column("timestamp"), status_column = column("status");
  std::set<double> unmeasured;
  for (int number = 2; std::getline(in, line); ++number) {
    if (trim(line).empty()) continue;
    const std::vector<std::string> cells = splitCsvRow(line);
    if (cells.size() <= std::max(time_column, status_column)) throw InputError(path + ":" + std::to_string(number) + ": too few columns");
    if (cells[status_column].rfind("fallback", 0) != 0) continue;
    unmeasured.insert(parseNumbers(cells[time_column], path, number).at(0));
  }
  for (StampedPose& pose : trajectory) {
    // frames.csv writes 9 significant digits; a TUM file 9 decimals.
    const auto near = unmeasured.lower_bound(pose.timestamp - 1e-6 * std::max(1.0, std::abs(pose.timestamp)));
    if (near != unmeasured.end() && std::abs(*near - pose.timestamp) <= 1e-6 * std::max(1.0, std::abs(pose.timestamp))) {
      pose.measured = false;
    }
  }
}

std::string formatG2o(const PoseGraph& graph) {
  std::string text;
  char line[512];
  for (size_t i = 0; i < graph.poses().size(); ++i) {
    const Pose2& p = graph.poses()[i];
    std::snprintf(line, sizeof(line), "VERTEX_SE2 %zu %.9f %.9f %.9f\n", i, p.x, p.y, p.theta);
    text += line;
  }
  text += "FIX 0\n";
  for (const GraphEdge& e : graph.edges()) {
    const Eigen::Matrix3d& I = e.information;
    std::snprintf(line, sizeof(line), "EDGE_SE2 %d %d %.9f %.9f %.9f %.9g %.9g %.9g %.9g %.9g %.9g\n", e.from, e.to,
                  e.T_from_to.x, e.T_from_to.y, e.T_from_to.theta, I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2));
    text += line;
  }
  return text;
}

}  // namespace groundslam
