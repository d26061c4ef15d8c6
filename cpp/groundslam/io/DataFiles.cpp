#include "groundslam/io/DataFiles.hpp"

#include <cstdlib>
#include <dlfcn.h>
#include <filesystem>
#include <system_error>

namespace fs = std::filesystem;

namespace groundslam {

std::vector<std::string> installPrefixesOfRunningCode() {
  std::vector<std::string> prefixes;
  std::error_code error;
  const fs::path executable = fs::read_symlink("/proc/self/exe", error);
  if (!error) prefixes.push_back(executable.parent_path().parent_path().string());
  // The file this code was linked into, when it is not the executable: the Python module (P/lib/python3/
  // dist-packages/groundslam*.so, run by /usr/bin/python3) or a shared library of a program that embeds us.
  // (For the executable itself glibc may report argv[0], possibly relative: only an absolute path of another file.)
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&installPrefixesOfRunningCode), &info) != 0 && info.dli_fname != nullptr &&
      fs::path(info.dli_fname).is_absolute() && !fs::equivalent(info.dli_fname, executable, error)) {
    const fs::path module = fs::path(info.dli_fname).lexically_normal();
    for (fs::path dir = module.parent_path(); dir.has_relative_path(); dir = dir.parent_path()) {
      if (dir.filename() == "lib") {  // P/lib/...
        prefixes.push_back(dir.parent_path().string());
        break;
      }
    }
  }
  return prefixes;
}

std::vector<std::string> dataFileCandidates(const std::string& installed, const std::string& in_source) {
  std::vector<std::string> candidates;
  if (const char* dir = std::getenv("GROUNDSLAM_DATA_DIR"); dir && *dir) candidates.push_back((fs::path(dir) / installed).string());
  for (const std::string& prefix : installPrefixesOfRunningCode()) {
    candidates.push_back((fs::path(prefix) / "share" / "groundslam" / installed).string());
  }
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

std::string defaultConfigPath() { return dataFilePath("default.yaml", "config/default.yaml"); }

}  // namespace groundslam
