#pragma once
// A run's output folder, written so that nothing is lost. Results go to a fresh staging folder beside the
// target; they replace the target's previous results only when the run has finished (an atomic exchange of
// the two folders where the file system has one), so a failed or killed run leaves the previous results as
// they were. The target must
// be absent, empty, or hold only files a run writes: a folder with anything else in it (a dataset, the
// user's own files) is refused, never emptied.

#include <string>
#include <vector>

namespace groundslam {

class RunFolder {
 public:
  /// Checks that `target` may receive results and that none of `inputs` (files the run reads) lies inside
  /// it, then creates the staging folder. Throws InputError saying why not.
  RunFolder(const std::string& target, const std::vector<std::string>& inputs);
  /// Removes the staging folder unless it was committed: the target is left untouched.
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  /// Where a result file is written until commit (inside the staging folder).
  std::string path(const std::string& name) const;
  const std::string& stagingFolder() const { return staging_; }
  const std::string& target() const { return target_; }

  /// Puts the results in place of the target's previous ones and returns where they are now.
  std::string commit();
  /// For an interrupted run: the results go to the target when it held none, otherwise beside it
  /// (`TARGET.interrupted`) so the previous results stay. Returns where they are.
  std::string commitPartial();

  /// Names a run writes into its folder; a folder holding only these may be replaced.
  static const std::vector<std::string>& resultNames();

 private:
  std::string target_;
  std::string staging_;
  bool committed_ = false;
};

/// A new folder name for a run with no --out: `PARENT/YYYYmmdd_HHMMSS` (with `_2`, `_3` ... when taken).
std::string newRunFolderName(const std::string& parent);
/// Points `PARENT/latest` at `run_folder` (a relative symbolic link, replaced atomically). Returns false
/// and leaves it alone when `latest` exists and is not a symbolic link.
bool pointLatestAt(const std::string& parent, const std::string& run_folder);

}  // namespace groundslam
