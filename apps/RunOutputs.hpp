#pragma once
// Formatting of a run's per-frame table.
#include <string>
#include <vector>

#include "groundslam/pipeline/FrameResult.hpp"

namespace groundslam::apps {

/// `frames.csv`: index,timestamp,keypoints,matches,inliers,status, then per-stage milliseconds, total_ms.
std::string formatFramesCsv(const std::vector<FrameResult>& results, const std::vector<double>& load_ms);
int countFallbacks(const std::vector<FrameResult>& results);

}  // namespace groundslam::apps
