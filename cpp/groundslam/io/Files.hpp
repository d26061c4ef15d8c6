#pragma once
#include <string>

namespace groundslam {

/// Writes a whole file under a temporary name and renames it into place, so that an interrupted
/// write never leaves a half-written file that looks like a result. Throws InputError.
void writeFileAtomically(const std::string& path, const std::string& content);

/// The whole content of a text file. Throws InputError naming the file.
std::string readTextFile(const std::string& path);

}  // namespace groundslam
