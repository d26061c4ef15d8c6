#include "groundslam/io/DataFiles.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace fs = std::filesystem;

namespace groundslam {

std::vector<std::string> dataFileCandidates(const std::string& installed, const std::string& in_source) {
  std::vector<std::string> candidates;
  if (const char* dir = std::getenv("GROUNDSLAM_DATA_DIR"); dir && *dir) candidates.push_back((fs::path(dir) / installed).string());
  std::error_code error;
  const fs::path executable = fs::read_symlink("/proc/self/exe", error);
  if (!error) candidates.push_back((executable.parent_path().parent_path() / "share" / "groundslam" / installed).string());
  candidates.push_back((fs::path(GROUNDSLAM_INSTALL_DATA_DIR) / installed).string());
  candidates.push_back((fs::path(GROUNDSLAM_SOURCE_DIR) / in_source).string());
  return candidates;
}

std::string dataFilePath(const std::string& installed, const std::string& in_source) {
  const std::vector<std::string> candidates = dataFileCandidates(installed, in_source);
  for (const std::string& candidate : candidates) {
    std::error_code error;
    if (fs::is_regular_file(candidate, error)) return candidate;
  }
  return candidates.front();
}

std::string defaultVocabularyPath() { return dataFilePath("vocabulary/ground.gslmvoc", "config/vocabulary/ground.gslmvoc"); }

}  // namespace groundslam
