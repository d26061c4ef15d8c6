#include "groundslam/io/RunFolder.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <stdio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>

#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"

namespace fs = std::filesystem;

namespace groundslam {
namespace {

bool isResultName(const std::string& name) {
  const auto& names = RunFolder::resultNames();
  return std::find(names.begin(), names.end(), name) != names.end();
}

/// Entries of a folder that no run writes (empty for an earlier run's folder).
std::vector<std::string> foreignEntries(const fs::path& folder) {
  std::vector<std::string> foreign;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (!isResultName(name)) foreign.push_back(name);
  }
  return foreign;
}

/// Deletes an earlier run's results (only the names a run writes) and the folder when that empties it.
void removeResults(const fs::path& folder) {
  std::error_code ignored;
  for (const std::string& name : RunFolder::resultNames()) fs::remove_all(folder / name, ignored);
  fs::remove(folder, ignored);  // only succeeds when empty
}

bool isInside(const fs::path& path, const fs::path& folder) {
  const fs::path p = fs::weakly_canonical(path), f = fs::weakly_canonical(folder);
  auto pi = p.begin();
  for (auto fi = f.begin(); fi != f.end(); ++fi, ++pi) {
    if (fi->empty()) continue;  // a trailing separator
    if (pi == p.end() || *pi != *fi) return false;
  }
  return true;
}

void renameOrThrow(const fs::path& from, const fs::path& to) {
  if (::rename(from.c_str(), to.c_str()) != 0) {
    throw InputError(to.string() + ": cannot move the results into place: " + std::strerror(errno));
  }
}

}  // namespace

const std::vector<std::string>& RunFolder::resultNames() {
  static const std::vector<std::string> names = {
      "run.yaml", "config.yaml", "trajectory.tum", "groundtruth.tum", "frames.csv", "metrics.json", "loop_closures.csv",
      "candidates.csv", "relocalizations.csv", "graph.g2o", "map.gsmap", "localizations.csv", "localized.tum",
      "report.html", "report", "odometry"};
  return names;
}

RunFolder::RunFolder(const std::string& target, const std::vector<std::string>& inputs) : target_(target) {
  const fs::path folder(target);
  for (const std::string& input : inputs) {
    if (!input.empty() && isInside(input, folder)) {
      throw InputError("--out " + target + ": holds " + input + ", an input of this run; choose another output folder");
    }
  }
  std::error_code error;
  if (fs::is_symlink(folder, error)) throw InputError("--out " + target + ": is a symbolic link; name the folder itself");
  if (fs::exists(folder, error)) {
    if (!fs::is_directory(folder, error)) throw InputError("--out " + target + ": exists and is not a folder");
    const std::vector<std::string> foreign = foreignEntries(folder);
    if (!foreign.empty()) {
      throw InputError("--out " + target + ": the folder holds files a run does not write (" + foreign.front() +
                       (foreign.size() > 1 ? ", ..." : "") + "); refusing to replace it, choose another output folder");
    }
  }
  const fs::path parent = folder.parent_path().empty() ? fs::path(".") : folder.parent_path();
  fs::create_directories(parent, error);
  if (error) throw InputError(parent.string() + ": cannot create the output folder: " + error.message());
  staging_ = (parent / ("." + folder.filename().string() + ".staging-" + std::to_string(::getpid()))).string();
  if (::mkdir(staging_.c_str(), 0755) != 0) {
    throw InputError(staging_ + ": cannot create the staging folder: " + std::strerror(errno));
  }
}

RunFolder::~RunFolder() {
  if (committed_) return;
  std::error_code ignored;
  fs::remove_all(staging_, ignored);  // ours alone: created fresh by the constructor
}

std::string RunFolder::path(const std::string& name) const { return (fs::path(staging_) / name).string(); }

std::string RunFolder::commit() {
  const fs::path folder(target_), staging(staging_);
  const fs::path parent = folder.parent_path().empty() ? fs::path(".") : folder.parent_path();
  syncFolder(staging_);
  std::error_code error;
  if (!fs::exists(folder, error)) {
    renameOrThrow(staging, folder);
  } else if (fs::is_empty(folder, error)) {
    fs::remove(folder, error);
    renameOrThrow(staging, folder);
  } else if (::renameat2(AT_FDCWD, staging.c_str(), AT_FDCWD, folder.c_str(), RENAME_EXCHANGE) == 0) {
    removeResults(staging);  // the exchange put the previous results there
  } else {
    // No atomic exchange on this file system: the previous results are set aside first, so a failure between
    // the two renames leaves them whole under `.NAME.previous-PID`, never half-replaced.
    const fs::path previous = parent / ("." + folder.filename().string() + ".previous-" + std::to_string(::getpid()));
    renameOrThrow(folder, previous);
    try {
      renameOrThrow(staging, folder);
    } catch (...) {
      ::rename(previous.c_str(), folder.c_str());
      throw;
    }
    removeResults(previous);
  }
  committed_ = true;
  syncFolder(parent.string());
  return target_;
}

std::string RunFolder::commitPartial() {
  std::error_code error;
  const fs::path folder(target_);
  if (!fs::exists(folder, error) || fs::is_empty(folder, error)) return commit();
  const std::string aside = target_ + ".interrupted";
  if (fs::exists(aside, error)) {
    if (!fs::is_directory(aside, error) || !foreignEntries(aside).empty()) {
      committed_ = true;  // keep the staging folder: it is all there is of this run
      return staging_;
    }
    removeResults(aside);
  }
  renameOrThrow(staging_, aside);
  committed_ = true;
  return aside;
}

std::string newRunFolderName(const std::string& parent) {
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y%m%d_%H%M%S", &local);
  std::string name = (fs::path(parent) / stamp).string();
  std::error_code error;
  for (int n = 2; fs::exists(name, error); ++n) name = (fs::path(parent) / (std::string(stamp) + "_" + std::to_string(n))).string();
  return name;
}

bool pointLatestAt(const std::string& parent, const std::string& run_folder) {
  const fs::path latest = fs::path(parent) / "latest";
  std::error_code error;
  if (fs::exists(fs::symlink_status(latest, error)) && !fs::is_symlink(latest, error)) return false;
  const fs::path temporary = fs::path(parent) / (".latest-" + std::to_string(::getpid()));
  fs::remove(temporary, error);
  fs::create_directory_symlink(fs::path(run_folder).filename(), temporary, error);
  if (error) return false;
  if (::rename(temporary.c_str(), latest.c_str()) != 0) {
    fs::remove(temporary, error);
    return false;
  }
  return true;
}

}  // namespace groundslam
