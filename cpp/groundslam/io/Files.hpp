#pragma once
#include <string>

namespace groundslam {

/// Creates `path` and writes `content` to disk (fsync). Refuses a path that exists, even as a symbolic link,
/// so it never overwrites a file the caller did not create. On failure nothing is left behind. Throws
/// InputError with the system's reason ("No space left on device").
void writeNewFile(const std::string& path, const std::string& content);

/// Writes a whole file under a temporary name beside it, syncs it and renames it into place, so that an
/// interrupted write never leaves a half-written file that looks like a result. Throws InputError.
void writeFileAtomically(const std::string& path, const std::string& content);

/// Flushes a folder's entries (renames, new files) to disk. Errors are ignored: not every file system syncs folders.
void syncFolder(const std::string& path);

/// The whole content of a text file. Throws InputError naming the file.
std::string readTextFile(const std::string& path);

}  // namespace groundslam
