#pragma once
// Formatting of a run's per-frame table and metrics.
#include <memory>
#include <string>
#include <vector>

#include "groundslam/eval/LoopClosureMetrics.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/bow/Vocabulary.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/pipeline/Config.hpp"
#include "groundslam/pipeline/FrameResult.hpp"

namespace groundslam::apps {

/// `frames.csv`: index,timestamp,keypoints,matches,inliers,status, then per-stage milliseconds, total_ms.
std::string formatFramesCsv(const std::vector<FrameResult>& results, const std::vector<double>& load_ms);
/// Frames with this status.
int countStatus(const std::vector<FrameResult>& results, FrameStatus status);
int countLoopClosures(const std::vector<FrameResult>& results);
/// `metrics.json`: the trajectory metrics with the loop-closure metrics under "loop_closure".
std::string runMetricsJson(const TrajectoryMetrics& trajectory, const LoopClosureMetrics& loops);
/// Reads the vocabulary the settings name (`loop_closure.vocabulary`, else the shipped one); errors name the
/// key. Throws InputError.
std::shared_ptr<const Vocabulary> loadVocabulary(const InputSettings& inputs);
/// `run.yaml` of a run folder: `status: complete` or `interrupted`, frames processed and in the dataset.
/// `run.yaml`: whether the run finished, the dataset and the vocabulary file used (empty: none).
std::string runStatusYaml(const std::string& what, size_t processed, size_t total, const std::string& dataset,
                          const std::string& vocabulary);

}  // namespace groundslam::apps
