#pragma once
// The data files groundslam ships (the default vocabulary, the default configuration, the report script),
// found wherever the program runs: in an install prefix, in the source tree it was built from, or where the
// user says.

#include <string>
#include <vector>

namespace groundslam {

/// The install prefixes P the running code may come from: the executable's (P/bin/...) and, when this code is
/// in a shared object under P/lib (the Python module, a shared library), that P.
std::vector<std::string> installPrefixesOfRunningCode();

/// Where a shipped data file is looked for, in order: $GROUNDSLAM_DATA_DIR/<installed>; <dir of the running
/// executable>/../share/groundslam/<installed>; P/share/groundslam/<installed> when the code runs from a module
/// under P/lib (the Python module, a shared library); <install prefix>/share/groundslam/<installed>; <source
/// tree>/<in_source>.
std::vector<std::string> dataFileCandidates(const std::string& installed, const std::string& in_source);

/// The first candidate that exists; when none does, the first candidate (whose reader then names it).
std::string dataFilePath(const std::string& installed, const std::string& in_source);

/// The shipped vocabulary (`loop_closure.vocabulary` when that key is empty).
std::string defaultVocabularyPath();

/// The shipped default configuration: every key with its default value and a comment (a starting point to
/// copy and edit).
std::string defaultConfigPath();

}  // namespace groundslam
