#include "RunOutputs.hpp"

#include <cmath>
#include <cstdio>

#include "groundslam/io/DataFiles.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/VocabularyFile.hpp"

namespace groundslam::apps {

std::string formatFramesCsv(const std::vector<FrameResult>& results, const std::vector<double>& load_ms) {
  std::string csv =
      "index,timestamp,keypoints,matches,inliers,status,load_ms,extract_ms,project_ms,match_ms,fit_ms,loop_ms,"
      "optimise_ms,total_ms,odometry_x_m,odometry_y_m,odometry_theta_deg,still_matches,artifact_cells,roll_deg,pitch_deg,"
      "height_m,mount_estimated\n";
  char row[768];
  for (size_t i = 0; i < results.size(); ++i) {
    const FrameResult& r = results[i];
    const StageTimes& t = r.times;
    std::snprintf(row, sizeof(row),
                  "%d,%.9f,%d,%d,%d,%s,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.7f,%.7f,%.5f,%d,%d,%.4f,%.4f,%.6f,%d\n", r.index,
                  r.timestamp, r.keypoints, r.matches, r.inliers, r.statusName().c_str(), load_ms[i], t.extract_ms, t.project_ms,
                  t.match_ms, t.fit_ms, t.loop_ms, t.optimise_ms, load_ms[i] + t.total_ms, r.odometry.x, r.odometry.y,
                  r.odometry.theta * 180.0 / M_PI, r.still_matches, r.artifact_cells, r.mount.roll_rad * 180.0 / M_PI,
                  r.mount.pitch_rad * 180.0 / M_PI, r.mount.height_m, r.mount_estimated ? 1 : 0);
    csv += row;
  }
  return csv;
}

int countLoopClosures(const std::vector<FrameResult>& results) {
  int count = 0;
  for (const auto& r : results) count += r.loop_closures;
  return count;
}

std::string runMetricsJson(const TrajectoryMetrics& trajectory, const LoopClosureMetrics& loops) {
  std::string json = metricsToJson(trajectory);
  const size_t end = json.rfind('}');
  std::string loop_json = loopMetricsToJson(loops);
  // Indent the nested object by two spaces.
  std::string nested;
  for (char ch : loop_json) nested += ch == '\n' ? std::string("\n  ") : std::string(1, ch);
  json = json.substr(0, json.rfind('\n', end - 1)) + ",\n  \"loop_closure\": " + nested + "\n}\n";
  return json;
}

std::shared_ptr<const Vocabulary> loadVocabulary(const InputSettings& inputs) {
  try {
    return std::make_shared<const Vocabulary>(readVocabulary(vocabularyPath(inputs)));
  } catch (const InputError& e) {
    throw InputError(std::string("key 'loop_closure.vocabulary': ") + e.what());
  }
}

std::string runStatusYaml(const std::string& what, size_t processed, size_t total, const std::string& dataset,
                          const std::string& vocabulary) {
  const auto quoted = [](const std::string& text) {  // YAML single-quoted: quotes doubled
    std::string q = "'";
    for (char c : text) q += c == '\'' ? std::string("''") : std::string(1, c);
    return q + "'";
  };
  return "# groundslam " + what + " folder\nstatus: " + (processed < total ? "interrupted" : "complete") +
         "\nframes_processed: " + std::to_string(processed) + "\nframes_total: " + std::to_string(total) +
         "\ndataset: " + quoted(dataset) + "\nvocabulary: " + (vocabulary.empty() ? "null" : quoted(vocabulary)) + "\n";
}

int countStatus(const std::vector<FrameResult>& results, FrameStatus status) {
  int count = 0;
  for (const auto& r : results) count += r.status == status ? 1 : 0;
  return count;
}

}  // namespace groundslam::apps
