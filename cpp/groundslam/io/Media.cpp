#include "groundslam/io/Media.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <system_error>

#include "groundslam/io/DataFiles.hpp"
#include "groundslam/io/InputError.hpp"

namespace fs = std::filesystem;

namespace groundslam {
namespace {

constexpr const char* kModuleName = "groundslam_media.so";

const Media* load() {
  std::string tried;
  for (const std::string& candidate : mediaModuleCandidates()) {
    std::error_code error;
    if (!fs::is_regular_file(candidate, error)) {
      tried += "\n  " + candidate + " (not there)";
      continue;
    }
    void* handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = dlerror();
      tried += "\n  " + candidate + " (" + (why ? why : "cannot be loaded") + ")";
      continue;
    }
    using Create = const Media* (*)();
    const auto create = reinterpret_cast<Create>(dlsym(handle, GROUNDSLAM_MEDIA_ENTRY_NAME));
    if (!create) {
      tried += "\n  " + candidate + " (not this version of the module: no " + GROUNDSLAM_MEDIA_ENTRY_NAME + ")";
      dlclose(handle);
      continue;
    }
    if (const Media* media = create()) return media;  // kept loaded for the process's life
    tried += "\n  " + candidate + " (the module did not start)";
    dlclose(handle);
  }
  throw InputError("the OpenCV media module (" + std::string(kModuleName) +
                   ": image formats other than grey PNG / JPEG, video, writing images) was not found:" + tried +
                   "\nset GROUNDSLAM_MEDIA_MODULE to its path");
}

}  // namespace

std::vector<std::string> mediaModuleCandidates() {
  std::vector<std::string> candidates;
  if (const char* path = std::getenv("GROUNDSLAM_MEDIA_MODULE"); path && *path) candidates.emplace_back(path);
  for (const std::string& prefix : installPrefixesOfRunningCode()) {
    candidates.push_back((fs::path(prefix) / "lib" / "groundslam" / kModuleName).string());
  }
  candidates.emplace_back(GROUNDSLAM_BUILD_MEDIA_MODULE);
  candidates.push_back((fs::path(GROUNDSLAM_INSTALL_LIB_DIR) / "groundslam" / kModuleName).string());
  return candidates;
}

const Media& media() {
  static std::once_flag once;
  static const Media* loaded = nullptr;
  static std::string failure;
  std::call_once(once, [] {
    try {
      loaded = load();
    } catch (const InputError& e) {
      failure = e.what();
    }
  });
  if (!loaded) throw InputError(failure);
  return *loaded;
}

}  // namespace groundslam
